"""The Franka Panda through ``panda_py`` (extra ``bearchair[panda]``) with its wrist camera.

SDK facts this backend is written against (panda-python 1.1.1, libfranka 0.9.2; the
PyPI wheel fits the original Panda (FER) with robot system >= 4.2.1: research interface
version 5; other systems need the panda-py build for their libfranka version):

* ``Panda.get_pose()`` is ``O_T_EE``, the end effector set in Desk (with the Franka Hand
  10.34 cm along z and -45 deg about z from the flange). The hand-eye calibration is
  against the flange, so the camera pose is ``T_world_base @ O_T_EE @ inv(F_T_EE) @
  T_flange_camera`` with ``F_T_EE`` read from the robot state (column-major 16-vectors).
* ``move_to_joint_position`` blocks, returns False on failure (the libfranka error is
  kept for ``raise_error()``), and *first runs automatic error recovery* when the robot
  is in reflex: :meth:`PandaArm.move_to` therefore checks the robot's mode and errors
  itself and raises :class:`ArmFault` instead of letting a move recover silently.
* panda-py adds virtual joint walls :data:`JOINT_WALL_MARGIN_RAD` inside each limit
  (the PD zone of its ``VirtualWallController``): a target inside them is not reached.
* ``get_robot().stop()`` (libfranka ``Robot::stop``) preempts a running motion from
  another thread: :meth:`PandaArm.emergency_stop` uses it.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from bearchair.core.errors import BackendError, BackendUnavailable
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.hardware.real import EmergencyStopped, import_sdk
from bearchair.hardware.real.camera import CARMINE_INTRINSICS, CarmineCamera

__all__ = ["CARMINE_INTRINSICS", "ArmFault", "CarmineCamera", "PandaArm"]

log = logging.getLogger(__name__)

JOINT_LIMITS_LOWER_RAD = (-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973)
JOINT_LIMITS_UPPER_RAD = (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)
"""The Panda's (FER) joint limits, as libfranka and panda-py give them."""
JOINT_WALL_MARGIN_RAD = (0.12, 0.09, 0.09, 0.09, 0.0349, 0.0349, 0.0349)
"""panda-py's virtual wall PD-zone widths (``kPDZoneWidth``): it pushes joints out of this
band inside each limit."""
MAX_WALL_SHIFT_RAD = 0.1
"""A target at most this far inside the walls is moved to their edge (the camera pose
comes from the arm's own kinematics, so the view stays known); farther is refused."""
STILL_DURING_CAPTURE_M = 0.002
FAULT_MODES = ("kReflex", "kOther", "kUserStopped", "kAutomaticErrorRecovery")


class ArmFault(BackendError, RuntimeError):
    """The Panda reported an error (libfranka's message); recover it with the operator."""


def wall_limits() -> tuple[np.ndarray, np.ndarray]:
    """The joint range panda-py's walls leave (lower, upper) in radians."""
    margin = np.asarray(JOINT_WALL_MARGIN_RAD)
    return np.asarray(JOINT_LIMITS_LOWER_RAD) + margin, np.asarray(JOINT_LIMITS_UPPER_RAD) - margin


def into_walls(target: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """The target moved inside panda-py's walls, and a note per joint that moved.

    Raises:
        ValueError: a joint is more than :data:`MAX_WALL_SHIFT_RAD` beyond the walls.
    """
    lower, upper = wall_limits()
    clipped = np.clip(target, lower, upper)
    notes = []
    for joint in np.flatnonzero(np.abs(clipped - target) > 0.0):
        shift = float(clipped[joint] - target[joint])
        if abs(shift) > MAX_WALL_SHIFT_RAD:
            raise ValueError(
                f"joint {joint + 1} target {target[joint]:.4f} rad is {abs(shift):.3f} rad inside "
                f"panda-py's joint wall [{lower[joint]:.4f}, {upper[joint]:.4f}]: unreachable"
            )
        notes.append(f"joint {joint + 1} {target[joint]:.4f} -> {clipped[joint]:.4f} rad")
    return clipped, notes


def _mode_name(mode: Any) -> str:
    return getattr(mode, "name", str(mode).rsplit(".", 1)[-1])


STOP_POLL_S = 0.005
"""How often (seconds) a running move checks whether a stop must be repeated."""


class PandaArm:
    """:class:`bearchair.hardware.interfaces.ScanningArm` on a real Panda.

    Args:
        robot: a ``panda_py.Panda`` (tests pass :class:`bearchair.hardware.real.standins.FakePanda`).
        camera: the wrist camera (``read() -> (rgb, depth_m)`` and ``intrinsics``).
        T_world_base: the arm base in the world frame.
        T_flange_camera: the hand-eye calibration (camera optical frame in the flange frame).
        speed_factor: fraction of the arm's velocity limits for scanning moves.
    """

    def __init__(
        self,
        robot: Any,
        camera: Any,
        T_world_base: np.ndarray,
        T_flange_camera: np.ndarray,
        speed_factor: float = 0.2,
    ) -> None:
        self._robot = robot
        self._camera = camera
        self._T_world_base = np.asarray(T_world_base, dtype=float)
        self._T_flange_camera = np.asarray(T_flange_camera, dtype=float)
        self._speed_factor = speed_factor
        self._start = time.monotonic()
        self._stopped = False

    @classmethod
    def connect(
        cls,
        host: str,
        T_world_base: np.ndarray,
        T_flange_camera: np.ndarray,
        speed_factor: float = 0.2,
        openni_library_dir: str | None = None,
        camera: str = "carmine",
    ) -> PandaArm:
        """Connects to the arm's controller at ``host`` and opens the wrist camera
        ("carmine" or "realsense"); moves nothing."""
        panda_py = import_sdk("panda_py", "bearchair[panda]")
        try:
            robot = panda_py.Panda(host)
        except Exception as error:
            raise BackendUnavailable(f"cannot reach the Panda at {host}: {error}") from error
        if camera == "realsense":
            from bearchair.hardware.real.camera import RealSenseCamera

            wrist: Any = RealSenseCamera()
        else:
            wrist = CarmineCamera(library_dir=openni_library_dir)
        return cls(robot, wrist, T_world_base, T_flange_camera, speed_factor)

    @property
    def camera(self) -> Any:
        return self._camera

    def state(self) -> dict[str, Any]:
        """Mode and errors, for check-hardware (reads only)."""
        state = self._robot.get_state()
        return {
            "mode": _mode_name(state.robot_mode),
            "errors": str(state.current_errors) if bool(state.current_errors) else "none",
            "q_rad": np.round(np.asarray(state.q, dtype=float), 4).tolist(),
        }

    def joint_positions(self) -> np.ndarray:
        return np.asarray(self._robot.get_state().q, dtype=float)

    def move_to(self, joint_positions_rad: Sequence[float], timeout_s: float = 10.0) -> None:
        """Moves to a joint configuration within ``timeout_s`` (the arm is stopped if not).

        Raises:
            ValueError: not 7 finite angles, or beyond panda-py's joint walls.
            ArmFault: the arm is in reflex, user-stopped or reports errors (never
                recovered here), or libfranka raised during the move.
            TimeoutError: not reached in time (the arm was stopped).
            EmergencyStopped: the arm was emergency-stopped.
        """
        self._refuse_if_stopped()
        target = np.asarray(joint_positions_rad, dtype=float).reshape(-1)
        if target.shape != (7,) or not np.all(np.isfinite(target)):
            raise ValueError(f"the Panda has 7 joints, got {target.shape}")
        target, notes = into_walls(target)
        if notes:
            log.warning("Panda target moved inside the joint walls: %s", "; ".join(notes))
        self._raise_if_faulted()
        outcome: dict[str, Any] = {}

        def run() -> None:
            try:
                outcome["reached"] = self._robot.move_to_joint_position(
                    target, speed_factor=self._speed_factor
                )
            except Exception as error:  # libfranka's exceptions arrive here
                outcome["error"] = error

        worker = threading.Thread(target=run, name="panda-move", daemon=True)
        worker.start()
        deadline = time.monotonic() + timeout_s
        while worker.is_alive() and time.monotonic() < deadline:
            # Polled at 200 Hz: a stop that lands between two moves is repeated within 5 ms.
            worker.join(min(STOP_POLL_S, max(0.0, deadline - time.monotonic())))
            if self._stopped and worker.is_alive():
                # A stop sent just before the move began has nothing to stop: repeat it.
                self._stop_robot()
        if worker.is_alive():
            self._stop_robot()
            worker.join(2.0)
            raise TimeoutError(f"the Panda did not reach its target in {timeout_s:.1f} s (stopped)")
        self._refuse_if_stopped()
        if "error" in outcome:
            raise ArmFault(f"the Panda faulted: {outcome['error']}") from outcome["error"]
        if not outcome.get("reached"):
            try:
                self._robot.raise_error()
            except Exception as error:
                raise ArmFault(f"the Panda faulted: {error}") from error
            raise TimeoutError(f"the Panda stopped short of {np.round(target, 3).tolist()}")

    def capture(self) -> RGBDFrame:
        T_base_flange = self._T_base_flange()
        rgb, depth_m = self._camera.read()
        moved_m = float(np.linalg.norm(self._T_base_flange()[:3, 3] - T_base_flange[:3, 3]))
        if moved_m > STILL_DURING_CAPTURE_M:
            raise RuntimeError(f"the Panda moved {moved_m * 1000:.1f} mm during a capture")
        return RGBDFrame(
            rgb=rgb,
            depth_m=depth_m,
            intrinsics=self._camera.intrinsics,
            T_world_camera=self._T_world_base @ T_base_flange @ self._T_flange_camera,
            stamp_s=time.monotonic() - self._start,
        )

    def emergency_stop(self) -> None:
        """Preempts any running move through libfranka's ``Robot::stop``; latching."""
        self._stopped = True
        self._stop_robot()

    def _T_base_flange(self) -> np.ndarray:
        state = self._robot.get_state()
        O_T_EE = np.asarray(state.O_T_EE, dtype=float).reshape(4, 4).T
        F_T_EE = np.asarray(state.F_T_EE, dtype=float).reshape(4, 4).T
        return O_T_EE @ np.linalg.inv(F_T_EE)

    def _raise_if_faulted(self) -> None:
        state = self._robot.get_state()
        mode = _mode_name(state.robot_mode)
        if mode in FAULT_MODES or bool(state.current_errors):
            raise ArmFault(
                f"the Panda is in {mode} with errors {state.current_errors}: clear it with the "
                "operator (Desk, or panda.recover() with nobody near the arm), then run again"
            )

    def _stop_robot(self) -> None:
        with contextlib.suppress(Exception):
            self._robot.get_robot().stop()

    def _refuse_if_stopped(self) -> None:
        if self._stopped:
            raise EmergencyStopped("the Panda is emergency-stopped: motion refused")
