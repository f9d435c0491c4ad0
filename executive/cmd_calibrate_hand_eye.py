"""``bearchair calibrate-hand-eye``: the wrist camera's ``T_flange_camera`` from views of a board.

Three ways in, one of them per call:

* ``--robots cell.json``: connects the Panda and its camera (moves nothing), says what
  will move and asks (``--yes`` skips the question; no terminal counts as no); then moves
  the arm at a tenth of its speed limits to HOME and through the first ``--views`` of
  :data:`bearchair.skills.perception.hand_eye.CALIBRATION_CONFIGURATIONS`, back to HOME between
  views (each motion is the straight joint-space motion from HOME that was checked),
  captures a frame at each, finds the board, solves and ends at HOME. A failed motion
  or Ctrl-C stops the arm (libfranka's ``Robot::stop``).
* ``--from views.json``: solves again from the views a ``--out`` file recorded (no robot).
* ``--board-png FILE``: writes the printable board (300 dpi) and exits.

It prints one line per view, the residuals, and ``T_flange_camera`` as the line the cell
file takes. The flange poses come from each frame's own pose, which the backend computes
as ``T_world_base @ O_T_EE @ inv(F_T_EE) @ T_flange_camera`` with the cell file's
(uncalibrated) values, so they are inverted out exactly and do not bias the answer.

Exit status: 0 solved, the board's pose agreeing over the views within
:data:`~skills.perception.hand_eye.MAX_SPREAD_MM` and
:data:`~skills.perception.hand_eye.MAX_SPREAD_DEG`, and the depth camera's distance to the
board within :data:`~skills.perception.hand_eye.MAX_SCALE_ERROR` of what the printed
size gives (the residuals cannot see a wrong square size); 1 solved but one of those
fails (the answer is printed, marked not to use); 2 a wrong cell file or views file, the
operator said no, too few views with the board, rotations too alike.
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from bearchair.executive.cli_types import positive_int, positive_seconds

if TYPE_CHECKING:
    from bearchair.executive.cell_config import CellConfig
    from bearchair.hardware.real.panda import PandaArm

SETTLE_S = 0.5
"""Wait after each motion before capturing: the arm's last vibration and the camera's
auto-exposure after the view changed."""
MOVE_TIMEOUT_S = 120.0
"""One motion at a tenth of the speed limits: the longest (about 2 rad of joint 7)
takes about 10 s on the Panda."""


def register(subparsers: Any) -> None:
    parser = subparsers.add_parser(
        "calibrate-hand-eye",
        help="the wrist camera's T_flange_camera from views of a ChArUco board (moves the arm)",
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument(
        "--robots", type=Path, metavar="CELL_JSON", help="move the arm of this cell and capture"
    )
    source.add_argument(
        "--from",
        dest="from_file",
        type=Path,
        metavar="VIEWS_JSON",
        help="solve again from the views a previous --out recorded (no robot)",
    )
    source.add_argument(
        "--board-png", type=Path, metavar="PNG", help="write the printable board and exit"
    )
    parser.add_argument(
        "--views",
        type=positive_int,
        help="how many of the stored calibration views to visit (3 to 9, default all)",
    )
    parser.add_argument(
        "--square-mm",
        type=float,
        default=None,
        help="the printed board's square side as measured, millimetres (default 30)",
    )
    parser.add_argument("--out", type=Path, help="also write the views and the answer (JSON)")
    parser.add_argument("--yes", action="store_true", help="with --robots: move without asking")
    parser.add_argument(
        "--timeout",
        type=positive_seconds,
        default=5.0,
        help="seconds the arm and the camera may take to answer (not the motions)",
    )
    parser.set_defaults(func=calibrate_hand_eye)


class View(NamedTuple):
    """One capture: where the flange was and where the camera saw the board.

    Attributes:
        name: ``calib<i>``, the stored configuration's index.
        configuration_rad: the arm's joint angles at the capture.
        T_base_flange: the flange in the arm's base frame (4x4, metres).
        detection: the board's pose in the camera frame, None when it was not seen.
        note: why the board was not seen.
        depth_ratio: the depth image's distance to the board over its pose's
            (:func:`bearchair.skills.perception.charuco.board_depth_ratio`), None without depth.
    """

    name: str
    configuration_rad: tuple[float, ...]
    T_base_flange: np.ndarray
    detection: Any | None
    note: str = ""
    depth_ratio: float | None = None


def _error(message: str) -> Exception:
    from bearchair.core.errors import InputError

    return InputError(f"bearchair calibrate-hand-eye: {message}")


def _board(args: argparse.Namespace, recorded: dict[str, Any] | None = None) -> Any:
    from bearchair.skills.perception.charuco import CALIBRATION_BOARD, BoardSpec

    board = CALIBRATION_BOARD
    if recorded is not None:
        try:
            board = BoardSpec(**recorded)
        except TypeError as error:
            raise _error(f"--from: the board entry is not a board ({error})") from None
    if args.square_mm is not None:
        if not 5.0 <= args.square_mm <= 200.0:
            raise _error(f"--square-mm {args.square_mm:g}: a printed square is 5-200 mm")
        board = board.printed_at(args.square_mm / 1000.0)
    return board


def calibrate_hand_eye(args: argparse.Namespace) -> int:
    from bearchair.executive.outputs import check_output_file

    if args.board_png is not None:
        return _write_board(args)
    if args.out is not None:
        check_output_file(args.out, "--out", (".json",))
    if args.from_file is not None:
        if args.views is not None or args.yes:
            raise _error("--views and --yes are for --robots, not --from")
        recorded, views = _load_views(args.from_file)
        board = _board(args, recorded._asdict())
        if board.square_m != recorded.square_m:
            # PnP on a board scaled by s gives the same rotation and s times the
            # translation: a square measured after the capture rescales the recorded poses.
            views = [_rescaled(view, board.square_m / recorded.square_m) for view in views]
    else:
        board = _board(args)
        views = _capture(args, board)
    return _solve_and_report(views, board, args.out)


def _rescaled(view: View, factor: float) -> View:
    if view.detection is None:
        return view
    T = view.detection.T_camera_board.copy()
    T[:3, 3] *= factor
    ratio = None if view.depth_ratio is None else view.depth_ratio / factor
    return view._replace(detection=view.detection._replace(T_camera_board=T), depth_ratio=ratio)


def _write_board(args: argparse.Namespace) -> int:
    import cv2

    from bearchair.executive.outputs import atomic_path, check_output_file
    from bearchair.skills.perception.charuco import board_image

    if args.views is not None or args.yes or args.out is not None:
        raise _error("--board-png writes the board only; no --views, --yes or --out")
    path = check_output_file(args.board_png, "--board-png", (".png",))
    board = _board(args)
    with atomic_path(path) as scratch:
        if not cv2.imwrite(str(scratch), board_image(board)):
            raise _error(f"--board-png {path}: could not write the picture")
    print(
        f"board: {path} ({board.squares_x} x {board.squares_y} squares of "
        f"{board.square_m * 1000:g} mm, markers {board.dictionary}); print it at 100 % "
        "(300 dpi), measure a square, and give that as --square-mm if it is not "
        f"{board.square_m * 1000:g} mm"
    )
    return 0


def _capture(args: argparse.Namespace, board: Any) -> list[View]:
    """Connects, asks, moves through the views and captures; always ends at HOME."""
    from bearchair.executive.cell_config import load_cell_config
    from bearchair.executive.cmd_check_hardware import MOVE_SPEED_FACTOR
    from bearchair.executive.operator import ask_operator, not_asked_because
    from bearchair.hardware.real import robots
    from bearchair.hardware.real.bounded import call_within
    from bearchair.skills.perception.hand_eye import (
        BOARD_CENTRE_BASE_XY_M,
        CALIBRATION_CONFIGURATIONS,
    )

    count = len(CALIBRATION_CONFIGURATIONS) if args.views is None else args.views
    if not 3 <= count <= len(CALIBRATION_CONFIGURATIONS):
        raise _error(f"--views {count}: from 3 to {len(CALIBRATION_CONFIGURATIONS)}")
    cell = load_cell_config(args.robots)  # CellConfigError: one line, exit 2
    arm = call_within(args.timeout, lambda: robots.connect_panda(cell), "the Panda")
    state = call_within(args.timeout, arm.state, "the Panda")
    if state["mode"] not in ("kIdle", "kMove") or state["errors"] != "none":
        raise _error(
            f"the Panda is in {state['mode']} with errors {state['errors']}: clear it in Desk "
            "with the operator first; nothing moved"
        )
    x, y = BOARD_CENTRE_BASE_XY_M
    print(
        f"calibrate-hand-eye: the board ({board.squares_x} x {board.squares_y} squares of "
        f"{board.square_m * 1000:g} mm) lies flat on the floor, face up, its centre at "
        f"({x:g}, {y:g}) m in the arm's base frame, nothing else within 0.3 m of it. The "
        f"arm moves to HOME and through {count} views, back to HOME between them, at "
        f"{MOVE_SPEED_FACTOR:g} of its speed limits.",
        flush=True,
    )
    if not args.yes and not ask_operator("The Panda will move now. Go on? [y/N] "):
        reason = not_asked_because()
        raise _error(
            "the operator did not confirm: nothing moved" + (f" ({reason})" if reason else "")
        )
    arm.speed_factor = MOVE_SPEED_FACTOR  # as check-hardware --move: slow, near a person
    return _visit_views(arm, cell, board, CALIBRATION_CONFIGURATIONS[:count], args.timeout)


def _visit_views(
    arm: PandaArm,
    cell: CellConfig,
    board: Any,
    configurations: Sequence[Sequence[float]],
    timeout_s: float,
) -> list[View]:
    """HOME, then each configuration (capture, detect the board) and back to HOME; any
    failure emergency-stops the arm."""
    from bearchair.core.errors import BackendUnavailable
    from bearchair.executive.interrupts import emergency_stop_on_second_signal
    from bearchair.hardware.real.bounded import call_within
    from bearchair.skills.perception.views import HOME_CONFIGURATION

    T_base_world = np.linalg.inv(cell.T_world_base)
    T_camera_flange = np.linalg.inv(cell.T_flange_camera)
    views: list[View] = []
    where = "HOME"
    with emergency_stop_on_second_signal(arm.emergency_stop):
        try:
            arm.move_to(HOME_CONFIGURATION, timeout_s=MOVE_TIMEOUT_S)
            for index, joints in enumerate(configurations):
                where = f"view calib{index}"
                arm.move_to(joints, timeout_s=MOVE_TIMEOUT_S)
                time.sleep(SETTLE_S)
                call_within(
                    timeout_s, arm.capture, "the wrist camera"
                )  # buffered during the motion
                frame = call_within(timeout_s, arm.capture, "the wrist camera")
                T_base_flange = T_base_world @ frame.T_world_camera @ T_camera_flange
                view = _detect(f"calib{index}", arm.joint_positions(), T_base_flange, frame, board)
                _print_view(view)
                views.append(view)
                where = f"HOME after view calib{index}"
                arm.move_to(HOME_CONFIGURATION, timeout_s=MOVE_TIMEOUT_S)
        except Exception as error:  # a fault, a timeout, a camera error: stop, one line
            arm.emergency_stop()
            raise BackendUnavailable(
                f"calibrate-hand-eye: stopped the Panda on the way to {where}: {error}"
            ) from error
        except BaseException:  # Ctrl-C, SIGTERM: stop the arm, then let it through
            arm.emergency_stop()
            raise
    return views


def _detect(
    name: str, joints: np.ndarray, T_base_flange: np.ndarray, frame: Any, board: Any
) -> View:
    from bearchair.skills.perception.charuco import board_depth_ratio, detect_board
    from bearchair.skills.perception.errors import BoardNotSeenError

    configuration = tuple(round(float(q), 4) for q in joints)
    try:
        detection = detect_board(frame.rgb, frame.intrinsics, board)
    except BoardNotSeenError as error:
        return View(name, configuration, T_base_flange, None, str(error))
    ratio = board_depth_ratio(detection, frame.depth_m, frame.intrinsics, board)
    return View(name, configuration, T_base_flange, detection, depth_ratio=ratio)


def _print_view(view: View) -> None:
    if view.detection is None:
        print(f"[warn] view {view.name}: {view.note}", flush=True)
        return
    distance = float(np.linalg.norm(view.detection.T_camera_board[:3, 3]))
    depth = "no depth on it" if view.depth_ratio is None else f"depth/board {view.depth_ratio:.3f}"
    print(
        f"[  ok] view {view.name}: board {distance:.3f} m away, {view.detection.corners} "
        f"corners, {view.detection.reprojection_rms_px:.2f} px RMS, {depth}",
        flush=True,
    )


def _solve_and_report(views: list[View], board: Any, out: Path | None) -> int:
    from bearchair.skills.perception.errors import HandEyeError
    from bearchair.skills.perception.hand_eye import (
        MAX_SCALE_ERROR,
        MAX_SPREAD_DEG,
        MAX_SPREAD_MM,
        MIN_VIEWS,
        solve_hand_eye,
    )

    seen = [view for view in views if view.detection is not None]
    if len(seen) < MIN_VIEWS:
        raise HandEyeError(
            f"hand-eye: the board was seen in {len(seen)} of {len(views)} views, at least "
            f"{MIN_VIEWS} needed (is it flat on the floor where the command said?)"
        )
    if len(seen) < len(views):
        print(f"calibrate-hand-eye: the board was seen in {len(seen)} of {len(views)} views")
    result = solve_hand_eye(
        [view.T_base_flange for view in seen],
        [detection.T_camera_board for view in seen if (detection := view.detection) is not None],
    )
    residuals = result.residuals
    for view, mm, deg in zip(seen, residuals.translation_mm, residuals.rotation_deg, strict=True):
        print(f"residual {view.name}: board {mm:.2f} mm, {deg:.3f} deg from the mean")
    print(
        f"calibrate-hand-eye: {result.views} views, rotations {result.rotation_diversity_deg:.1f} "
        f"deg about a second axis; the board's pose in the base frame agrees within "
        f"{residuals.max_mm:.2f} mm (RMS {residuals.rms_mm:.2f}) and {residuals.max_deg:.3f} deg "
        f"(RMS {residuals.rms_deg:.3f})"
    )
    ratios = [view.depth_ratio for view in seen if view.depth_ratio is not None]
    scale = float(np.median(ratios)) if ratios else None
    if scale is None:
        print("calibrate-hand-eye: no depth on the board: its printed size is not checked")
    else:
        print(
            f"calibrate-hand-eye: the depth camera puts the board at {scale:.3f} of the "
            f"distance its {board.square_m * 1000:g} mm squares give (median of {len(ratios)} views)"
        )
    print("T_flange_camera for the cell file:")
    print(json.dumps(result.cell_entry()))
    if out is not None:
        _write_views(out, views, board, result)
        print(f"views and answer: {out}")
    problems = []
    if not residuals.acceptable():
        problems.append(
            f"the views disagree by more than {MAX_SPREAD_MM:g} mm or {MAX_SPREAD_DEG:g} deg "
            "(a board that moved, wrong intrinsics?)"
        )
    if scale is not None and abs(scale - 1.0) > MAX_SCALE_ERROR:
        problems.append(
            f"the depth camera measures the board {100 * (scale - 1):+.1f} % from its printed "
            f"size (at most {100 * MAX_SCALE_ERROR:g} %): measure a square and give "
            "--square-mm; if it was right, the camera's focal length is off by as much: "
            "calibrate camera_intrinsics (docs/real-robots.md)"
        )
    if not problems:
        return 0
    print(f"calibrate-hand-eye: NOT GOOD ENOUGH: {'; '.join(problems)}: do not use this answer")
    return 1


def _write_views(path: Path, views: list[View], board: Any, result: Any) -> None:
    from bearchair.executive.outputs import write_text_atomic

    record = {
        "board": board._asdict(),
        "T_flange_camera": result.cell_entry()["T_flange_camera"],
        "residuals": result.residuals.to_json(),
        "rotation_diversity_deg": round(result.rotation_diversity_deg, 3),
        "views": [
            {
                "name": view.name,
                "configuration_rad": list(view.configuration_rad),
                "T_base_flange": view.T_base_flange.tolist(),
                "T_camera_board": None
                if view.detection is None
                else view.detection.T_camera_board.tolist(),
                "corners": None if view.detection is None else view.detection.corners,
                "reprojection_rms_px": None
                if view.detection is None
                else round(view.detection.reprojection_rms_px, 4),
                "depth_ratio": None if view.depth_ratio is None else round(view.depth_ratio, 5),
                "note": view.note,
            }
            for view in views
        ],
    }
    write_text_atomic(path, json.dumps(record, indent=2) + "\n")


MAX_VIEWS = 200
"""Most views a ``--from`` file may hold: a calibration takes 9 to a few dozen, and
solving A X = X B over every pair of 200 views (19900 pairs) takes seconds."""


def _what_is_wrong(error: Exception) -> str:
    """A recorded file's defect in words, not a Python repr."""
    from bearchair.core.userfiles import printable

    if isinstance(error, KeyError):
        return f"a view or the board lacks the field {printable(error.args[0] if error.args else '', 40)}"
    return printable(str(error) or type(error).__name__, 120)


def _load_views(path: Path) -> tuple[Any, list[View]]:
    """The board and views of a ``--out`` file (exact matrices, as written)."""
    from bearchair.core.errors import InputError
    from bearchair.core.userfiles import load_user_json, printable

    try:
        record = load_user_json(path, "calibration file", InputError)
    except InputError as error:
        raise _error(f"--from {error}") from None
    if not isinstance(record, dict) or not isinstance(record.get("views"), list):
        raise _error(
            f'--from {printable(path)}: not a calibrate-hand-eye --out file (no "views" list)'
        )
    if len(record["views"]) > MAX_VIEWS:
        raise _error(
            f"--from {printable(path)}: {len(record['views'])} views, more than the "
            f"{MAX_VIEWS} a calibration uses (A X = X B pairs grow as the square of the views)"
        )
    from bearchair.skills.perception.charuco import BoardDetection, BoardSpec

    try:
        board = BoardSpec(**record["board"])
        views = []
        for entry in record["views"]:
            detection = None
            if entry["T_camera_board"] is not None:
                detection = BoardDetection(
                    np.asarray(entry["T_camera_board"], dtype=float),
                    int(entry["corners"]),
                    float(entry["reprojection_rms_px"]),
                )
            views.append(
                View(
                    str(entry["name"]),
                    tuple(entry["configuration_rad"]),
                    np.asarray(entry["T_base_flange"], dtype=float),
                    detection,
                    str(entry.get("note", "")),
                    None if entry.get("depth_ratio") is None else float(entry["depth_ratio"]),
                )
            )
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
        raise _error(
            f"--from {printable(path)}: not a calibrate-hand-eye --out file "
            f"({_what_is_wrong(error)})"
        ) from None
    return board, views
