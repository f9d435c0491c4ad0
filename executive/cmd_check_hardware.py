"""``bearchair check-hardware --robots cell.json [--move [--walk]]``: check the cell.

Prints one line per check, ``ok``, ``warn`` or ``FAIL``: the cell file, the SDK versions,
the NAO's state (awake, Autonomous Life, BasicAwareness, battery, arm swing), the Panda's
mode, errors and joint limits, every arm configuration the mission uses against
panda-py's joint walls, the camera (modes, mirroring read back, intrinsics and where
they came from), one frame (depth units, valid pixels) and whether the NAO's tag is in it.
Each device gets ``--timeout`` seconds (default 5) for each answer, so an unreachable
or silent one fails naming itself, never hangs; Ctrl-C and SIGTERM end it at once.
Only ``--move`` moves anything: the arm to HOME, then its overview configuration (where
the tag is looked for), at a tenth of its speed limits (Ctrl-C stops the arm).
``--walk`` (with ``--move``, the bear *out of* the NAO's arms) also measures on the NAO
what NAOqi's documentation leaves open (:mod:`bearchair.executive.walk_check`).

Exit status: 0 every check passed (warnings allowed), 1 a check failed (the last line
names the failing devices), 2 the cell file is wrong.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from bearchair.core.userfiles import printable
from bearchair.hardware.real.bounded import call_within

MOVE_SPEED_FACTOR = 0.1


class _Report:
    def __init__(self) -> None:
        self.failed: list[str] = []

    def line(self, status: str, device: str, detail: str) -> None:
        print(f"[{status:>4}] {printable(device)}: {printable(detail, 1000)}", flush=True)
        if status == "FAIL" and device not in self.failed:
            self.failed.append(device)


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "check-hardware", help="check the robots of a cell file (moves nothing without --move)"
    )
    parser.add_argument(
        "--robots",
        type=Path,
        required=True,
        metavar="CELL_JSON",
        help="the cell file describing the NAO, the Panda and the camera to check",
    )
    parser.add_argument(
        "--move", action="store_true", help="also move the arm to its overview view, slowly"
    )
    parser.add_argument(
        "--walk",
        action="store_true",
        help="with --move: also walk the NAO (bear out of its arms) to measure its stop",
    )
    parser.add_argument(
        "--timeout", type=float, default=5.0, help="seconds each device may take to answer"
    )
    parser.set_defaults(func=check_hardware)


def _describe(error: BaseException) -> str:
    return (str(error) or type(error).__name__).splitlines()[0]


def check_hardware(args: argparse.Namespace) -> int:
    from bearchair.executive.cell_config import load_cell_config
    from bearchair.hardware.real import SDK_DISTRIBUTIONS, sdk_versions
    from bearchair.hardware.real.panda import into_walls

    # Imported before any device is waited on (it imports open3d, about a second): a stop
    # signal is handled between bytecodes, so it would wait for an import in progress.
    from bearchair.skills.perception.views import (
        HOME_CONFIGURATION,
        OVERVIEW_CONFIGURATION,
        SCAN_CONFIGURATIONS,
    )

    if not args.timeout > 0:
        from bearchair.core.errors import InputError

        raise InputError("bearchair check-hardware: --timeout must be positive")
    if args.walk and not args.move:
        from bearchair.core.errors import InputError

        raise InputError("bearchair check-hardware: --walk moves the NAO: give --move too")
    report = _Report()
    cell = load_cell_config(args.robots)  # CellConfigError: one line, exit 2
    report.line("ok", "cell", f"{args.robots} (NAO {cell.nao_url}, Panda {cell.panda_host})")
    for distribution, version in sdk_versions().items():
        extra = SDK_DISTRIBUTIONS[distribution]
        status = "ok" if version else ("FAIL" if extra in ("nao", "panda") else "warn")
        if extra == cell.camera and not version:
            status = "FAIL"
        detail = version or f"not installed (pip install 'bearchair[{extra}]')"
        report.line(status, f"sdk {distribution}", detail)

    for role, section in cell.devices.items():  # plug-in backends: their own business
        report.line("warn", role, f"plug-in backend {section['backend']!r}: not checked here")
    # The devices first: an unreachable one is reported before the slower checks.
    session = _check_nao(cell, args.timeout, report) if cell.nao_url is not None else None
    arm = _check_panda(cell, args.timeout, report) if cell.panda_host is not None else None

    views = {"HOME": HOME_CONFIGURATION, "OVERVIEW": OVERVIEW_CONFIGURATION}
    views.update({f"scan{i}": q for i, q in enumerate(SCAN_CONFIGURATIONS)})
    limits = arm.joint_limits if arm is not None else None
    for name, joints in views.items():
        try:
            _, notes = into_walls(np.asarray(joints, dtype=float), limits)
        except ValueError as error:
            report.line("FAIL", f"view {name}", _describe(error))
            continue
        if notes:
            report.line(
                "warn", f"view {name}", "inside panda-py's joint walls, moved: " + "; ".join(notes)
            )
        else:
            report.line("ok", f"view {name}", "clear of the joint walls")

    if arm is not None:
        _check_camera(arm, args.timeout, report, move=args.move)
    if args.walk and session is not None and "nao" not in report.failed:
        from bearchair.executive.walk_check import check_walk

        check_walk(session, cell, args.timeout, report.line)
    if session is not None:
        session.close(_async=True)  # never waited for: the link may be the problem
    if report.failed:
        print(f"check-hardware: FAILED: {', '.join(report.failed)}")
        return 1
    print("check-hardware: all checks passed" + ("" if args.move else " (nothing moved)"))
    return 0


def _check_nao(cell: Any, timeout_s: float, report: _Report) -> Any:
    """The NAO's state, read only; its qi session (None when it failed)."""
    from bearchair.hardware.real.nao import NaoHumanoid, connect

    try:
        session = connect(cell.nao_url, cell.nao_user, cell.nao_password, timeout_s=timeout_s)
    except Exception as error:
        report.line("FAIL", "nao", _describe(error))
        return None
    try:
        # Every NAOqi call is bounded by timeout_s inside the backend.
        state = NaoHumanoid(session, cell.nao_start, call_timeout_s=timeout_s).state()
    except Exception as error:
        report.line("FAIL", "nao", f"at {cell.nao_url}: {_describe(error)}")
        session.close(_async=True)
        return None
    report.line("ok", "nao", f"reached at {cell.nao_url}")
    report.line("ok", "nao awake", str(state["awake"]))
    life = state["autonomous_life"]
    report.line(
        "ok" if life == "disabled" else "warn",
        "nao autonomous life",
        f"{life}" + ("" if life == "disabled" else " (the mission turns it off)"),
    )
    report.line(
        "ok" if not state["basic_awareness"] else "warn",
        "nao basic awareness",
        f"{state['basic_awareness']}"
        + (" (the mission turns it off)" if state["basic_awareness"] else ""),
    )
    battery = state["battery_percent"]
    report.line("ok" if battery >= 30 else "FAIL", "nao battery", f"{battery} %")
    report.line("ok", "nao arm swing", f"{state['arm_swing']} (the mission turns it off)")
    return session


def _check_panda(cell: Any, timeout_s: float, report: _Report) -> Any:
    from bearchair.hardware.real.robots import connect_panda

    try:
        arm = connect_panda(cell, timeout_s=timeout_s)
        state = call_within(timeout_s, arm.state, f"the Panda at {cell.panda_host}")
    except Exception as error:
        report.line("FAIL", "panda", _describe(error))
        return None
    faulted = state["mode"] not in ("kIdle", "kMove") or state["errors"] != "none"
    report.line(
        "FAIL" if faulted else "ok",
        "panda",
        f"mode {state['mode']}, errors {state['errors']}"
        + (": clear it in Desk with the operator" if faulted else ""),
    )
    lower, upper = arm.joint_limits
    report.line(
        "ok",
        "panda limits",
        f"from the robot: joint 6 [{lower[5]:.4f}, {upper[5]:.4f}] rad, joint 7 "
        f"[{lower[6]:.4f}, {upper[6]:.4f}] rad",
    )
    return None if faulted else arm


def _check_camera(arm: Any, timeout_s: float, report: _Report, move: bool) -> None:
    from bearchair.core.arena import HUMANOID_TAG
    from bearchair.skills.perception.tags import estimate_tag_pose

    if move and not _move_to_overview(arm, report):
        return
    mode = arm.camera.mode() if hasattr(arm.camera, "mode") else {}
    if "mirroring" in mode:
        report.line("ok", "camera mirroring", f"{mode['mirroring']} (read back from the streams)")
    if "intrinsics" in mode:
        report.line("ok", "camera intrinsics", mode["intrinsics"])
    try:
        frame = call_within(timeout_s, arm.capture, "the wrist camera")
    except Exception as error:
        report.line("FAIL", "camera", _describe(error))
        return
    valid = float(np.mean(frame.depth_m > 0.0))
    median = float(np.median(frame.depth_m[frame.depth_m > 0.0])) if valid > 0 else float("nan")
    report.line(
        "ok" if valid > 0.2 else "FAIL",
        "camera",
        f"{frame.rgb.shape[1]}x{frame.rgb.shape[0]} {mode.get('depth', '')}, depth in metres "
        f"(median {median:.3f} m), {100 * valid:.0f} % valid pixels",
    )
    pose = estimate_tag_pose(frame, HUMANOID_TAG)
    where = "at the overview view" if move else "from the arm's current pose (--move: overview)"
    if pose is None:
        report.line("warn", "tag", f"NAO tag {HUMANOID_TAG.marker_id} not seen {where}")
    else:
        report.line("ok", "tag", f"NAO at ({pose.x:.2f}, {pose.y:.2f}) m, {where}")


def _move_to_overview(arm: Any, report: _Report) -> bool:
    """Moves the arm slowly to HOME, then the overview; stops it on a failure or Ctrl-C."""
    from bearchair.executive.interrupts import emergency_stop_on_second_signal
    from bearchair.skills.perception.views import HOME_CONFIGURATION, OVERVIEW_CONFIGURATION

    arm.speed_factor = MOVE_SPEED_FACTOR
    try:
        with emergency_stop_on_second_signal(arm.emergency_stop):
            arm.move_to(HOME_CONFIGURATION)
            arm.move_to(OVERVIEW_CONFIGURATION)
    except BaseException as error:  # Ctrl-C and SIGTERM too: the arm stops first
        arm.emergency_stop()
        if not isinstance(error, Exception):
            raise
        report.line("FAIL", "panda move", _describe(error))
        return False
    report.line("ok", "panda move", f"at the overview view (speed factor {MOVE_SPEED_FACTOR})")
    return True
