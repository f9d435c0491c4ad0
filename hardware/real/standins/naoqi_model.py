"""The documented NAOqi the stand-in serves: NAOqi 2.8's method table, the NAO's joints
and limits, and qi futures for motions that take time or answer late.

The table is :file:`hardware/real/naoqi_api.json` (its ``source`` names the pages of the
NAOqi 2.8 documentation it was written from); the joints and limits are qibullet's
nao.urdf's.
"""

from __future__ import annotations

import contextlib
import functools
import json
import threading
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

from bearchair.core.runtime import RUNTIME

NAOQI_API_PATH = Path(__file__).resolve().parents[1] / "naoqi_api.json"
_QI_SCALARS = {"void": "Void", "bool": "Bool", "float": "Float", "int": "Int32"}
_QI_SCALARS.update({"string": "String", "ALValue": "Dynamic"})


@functools.cache
def naoqi_api() -> dict[str, Any]:
    """The NAOqi 2.8 method table (see :file:`naoqi_api.json` for its source)."""
    return json.loads(NAOQI_API_PATH.read_text())


def qi_type(qi: Any, name: str) -> Any:
    """The qi type of one of the table's C++ type names (``vector<float>``, ``ALValue``)."""
    if name.startswith("vector<") and name.endswith(">"):
        return qi.List(qi_type(qi, name[len("vector<") : -1]))
    return getattr(qi, _QI_SCALARS[name])


def documented(service: str, method: str) -> dict[str, Any]:
    """The table's entry for ``service.method``.

    Raises:
        KeyError: NAOqi 2.8 documents no such method (the stand-in must not serve it).
    """
    try:
        return naoqi_api()["services"][service][method]
    except KeyError:
        raise KeyError(f"{service}.{method} is not in NAOqi 2.8's API (naoqi_api.json)") from None


@functools.cache
def nao_joint_limits() -> dict[str, tuple[float, float]]:
    """Each NAO joint's (lower, upper) limit in radians, from qibullet's nao.urdf."""
    from bearchair.hardware.sim.nao_urdf import QIBULLET_NAO_URDF

    limits = {}
    chains = naoqi_api()["chains"]
    known = {joint for joints in chains.values() for joint in joints}
    for joint in ET.parse(QIBULLET_NAO_URDF).getroot().iter("joint"):
        limit = joint.find("limit")
        if joint.get("name") in known and limit is not None:
            limits[str(joint.get("name"))] = (
                float(limit.get("lower", "nan")),
                float(limit.get("upper", "nan")),
            )
    return limits


def resolve_joints(names: Any) -> list[str]:
    """NAOqi's joint or chain names as joints ("Body": all of them).

    Raises:
        RuntimeError: a name that is neither a NAO joint nor a chain.
    """
    chains = naoqi_api()["chains"]
    joints: list[str] = []
    for name in [names] if isinstance(names, str) else list(names):
        if name in ("Body", "Joints", "JointActuators"):
            joints += [joint for chain in chains.values() for joint in chain]
        elif name in chains:
            joints += chains[name]
        elif name in nao_joint_limits():
            joints.append(name)
        else:
            raise RuntimeError(f"ALMotion: {name!r} is not a NAO joint or chain")
    return joints


def check_angles(names: list[str], angles: list[list[float]]) -> None:
    """Raises RuntimeError for an angle outside its joint's limit (degrees, a wrong sign)."""
    limits = nao_joint_limits()
    for name, joint_angles in zip(names, angles, strict=True):
        lower, upper = limits[name]
        for angle in joint_angles:
            if not lower - 1e-3 <= angle <= upper + 1e-3:
                raise RuntimeError(
                    f"ALMotion: {name} {angle:.3f} rad is outside [{lower:.3f}, {upper:.3f}] "
                    "(NAOqi would clip it; the stand-in refuses)"
                )


class JointKeyframes(NamedTuple):
    """An ``angleInterpolation`` as its body plays it: per joint, its angles (rad) and
    the times (s from now) to reach them."""

    names: list[str]
    angles: list[list[float]]
    times: list[list[float]]


def answered_later(qi: Any, work: Callable[[], Any], delay_s: float) -> Any:
    """A qi future answered ``delay_s`` from now by ``work()`` (a future it returns is
    followed; cancelling the outer future cancels it)."""
    inner: list[Any] = []

    def cancel(promise: Any) -> None:
        for future in inner:
            future.cancel()
        if not inner:
            promise.setCanceled()

    promise = qi.Promise(cancel)

    def run() -> None:
        time.sleep(delay_s)
        try:
            value = work()
        except Exception as error:
            promise.setError(str(error))
            return
        if isinstance(value, qi.Future):
            inner.append(value)
            value.wait()
            if value.isCanceled():
                promise.setCanceled()
            elif value.hasError(0):
                promise.setError(value.error(0))
            else:
                promise.setValue(value.value(0))
        else:
            promise.setValue(value)

    RUNTIME.start_thread(run, name="naoqi-standin call")
    return promise.future()


def task_future(
    qi: Any,
    run: Callable[[threading.Event], None],
    value: Any = None,
    on_cancel: Callable[[], None] | None = None,
    cancel_delay_s: float = 0.0,
) -> tuple[Any, threading.Event]:
    """A qi future for ``run(cancelled)`` in a thread; cancelling it sets ``cancelled``
    (``cancel_delay_s`` later: the cancel request crosses the same slow link)."""
    cancelled = threading.Event()

    def cancel_now(promise: Any) -> None:
        cancelled.set()
        if on_cancel is not None:
            on_cancel()
        with contextlib.suppress(RuntimeError):  # it may have finished meanwhile
            promise.setCanceled()

    def cancel(promise: Any) -> None:
        if cancel_delay_s > 0.0:
            threading.Timer(cancel_delay_s, cancel_now, args=(promise,)).start()
        else:
            cancel_now(promise)

    promise = qi.Promise(cancel)

    def worker() -> None:
        try:
            run(cancelled)
        except Exception as error:
            if not cancelled.is_set():
                promise.setError(str(error))
            return
        if not cancelled.is_set():
            promise.setValue(value)

    RUNTIME.start_thread(worker, name="naoqi-standin task")
    return promise.future(), cancelled
