"""The scan's motions and captures: HOME first, the side looks, then each view as planned.

:func:`capture_scan` looks down from HOME, turns the base joint for side looks where the
object runs past the HOME view's side edges (a sofa), bounds the object's extent from
those looks (:func:`bearchair.skills.perception.clearance.chair_extent`), plans every view
against it (:func:`bearchair.skills.perception.clearance.plan_views`) and visits the plan.
A motion that still stops short (``TimeoutError``) skips that view after backing out; the
scan fails only when fewer than :data:`MIN_SCAN_VIEWS` views were captured.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from bearchair.core.progress import report as report_progress
from bearchair.hardware.interfaces import RGBDFrame, ScanningArm
from bearchair.skills.perception.clearance import (
    ArmClearance,
    ChairExtent,
    PlannedView,
    chair_extent,
    cut_sides,
    plan_views,
)
from bearchair.skills.perception.errors import PerceptionError
from bearchair.skills.perception.views import HOME_CONFIGURATION, VIEW_CLEARANCE_M

log = logging.getLogger(__name__)

MIN_SCAN_VIEWS = 5
"""Fewest captured views a scan accepts: the tracking views alone are 5, and 5 views
from around the arm's side still cover the seat and backrest."""

MAX_SIDE_TURN_RAD = math.pi / 2.0
"""The arm turns its base joint at most this far from HOME for the side looks: past a
quarter turn the camera would look back along the arm's own side, away from the cell."""


def capture_planned(
    arm: ScanningArm,
    planned: Sequence[PlannedView],
    cancel: threading.Event | None,
    cancelled: type[Exception] = PerceptionError,
    home: Sequence[float] = HOME_CONFIGURATION,
) -> tuple[list[RGBDFrame], list[str], dict[str, float]]:
    """Visits the planned views and captures a frame at each one not skipped.

    A motion that stops short (``TimeoutError``: something in the way that the plan did
    not foresee) is backed out of, to the last configuration reached and then HOME, and
    that view is skipped. Ends at HOME.

    Returns:
        (frames, notes, seconds): one note per view not captured as planned; wall time in
        ``motion`` and ``capture``.
    """
    frames: list[RGBDFrame] = []
    notes: list[str] = []
    seconds = {"motion": 0.0, "capture": 0.0}
    current: Sequence[float] = home
    for visited, view in enumerate(planned):
        report_progress("scan: views", visited, len(planned))
        if cancel is not None and cancel.is_set():
            raise cancelled("chair scan cancelled")
        if view.status == "skipped":
            notes.append(
                f"view {view.index} skipped: the arm would pass {100 * view.clearance_m:.0f} cm "
                "from the chair's extent"
            )
            continue
        if view.status == "replaced":
            notes.append(f"view {view.index} replaced by a higher view clear of the chair")
        tick = time.perf_counter()
        try:
            if view.via_home and tuple(current) != tuple(home):
                arm.move_to(home)
                current = home
            arm.move_to(view.joints)
        except TimeoutError as error:
            notes.append(f"view {view.index} skipped: {error}")
            log.warning("scan view %d not reached (%s): backing out", view.index, error)
            _back_out(arm, current, home)
            current = home
            continue
        finally:
            seconds["motion"] += time.perf_counter() - tick
        current = view.joints
        tick = time.perf_counter()
        frames.append(arm.capture())
        seconds["capture"] += time.perf_counter() - tick
    report_progress("scan: views", len(planned), len(planned))
    tick = time.perf_counter()
    if tuple(current) != tuple(home):
        arm.move_to(home)
    seconds["motion"] += time.perf_counter() - tick
    return frames, notes, seconds


def _back_out(arm: ScanningArm, last: Sequence[float], home: Sequence[float]) -> None:
    """Returns to the last configuration reached, then HOME, after a blocked motion."""
    for joints in (last, home):
        try:
            arm.move_to(joints)
        except TimeoutError as error:
            raise PerceptionError(
                f"the arm is stuck after a blocked scan motion: {error}"
            ) from error


class ScanCapture(NamedTuple):
    """What :func:`capture_scan` brings back.

    Attributes:
        frames: one per scan view captured, in visiting order.
        looks: the side looks from HOME turned (an object wider than the HOME view).
        notes: views skipped or replaced, side looks taken.
        seconds: wall time: ``motion``, ``capture``, ``plan``.
        extent: the object's extent the views were checked against.
    """

    frames: list[RGBDFrame]
    looks: list[RGBDFrame]
    notes: list[str]
    seconds: dict[str, float]
    extent: ChairExtent


def side_look_step_rad(frame: RGBDFrame) -> float:
    """How far the base joint turns between side looks: half the camera's horizontal field
    of view, so that each look overlaps the one before by half an image."""
    intr = frame.intrinsics
    return math.atan(intr.width / (2.0 * intr.fx))


def side_looks(
    arm: ScanningArm,
    home_frame: RGBDFrame,
    clearance: ArmClearance,
    home: Sequence[float] = HOME_CONFIGURATION,
) -> tuple[list[RGBDFrame], list[str]]:
    """Turns the arm's base joint from HOME toward each side where the object runs out of
    the HOME view (:func:`cut_sides`), a half field of view at a time, while it still runs
    out of the latest look, up to :data:`MAX_SIDE_TURN_RAD`; each turn checked against the
    extent seen so far (:data:`VIEW_CLEARANCE_M`). Ends at HOME.

    Returns:
        (the looks captured, a note per side looked at).
    """
    home = tuple(float(v) for v in home)
    T = np.asarray(home_frame.T_world_camera, float)
    forward, right = T[:3, 2], T[:3, 0]
    # Turning the base joint by +angle moves the view toward z x forward.
    left_sign = 1.0 if float(np.cross([0.0, 0.0, 1.0], forward) @ -right) > 0.0 else -1.0
    step = side_look_step_rad(home_frame)
    looks: list[RGBDFrame] = []
    notes: list[str] = []
    cut = cut_sides(home_frame)
    for side, sign in ((0, left_sign), (1, -left_sign)):
        if not cut[side]:
            continue
        current = home
        taken = 0
        turns = int(MAX_SIDE_TURN_RAD // step)
        for turn in range(1, turns + 1):
            joints = (home[0] + sign * turn * step, *home[1:])
            extent = chair_extent([home_frame, *looks])
            clearance.set_box(extent.lower, extent.upper)
            if clearance.path_clearance(current, joints) < VIEW_CLEARANCE_M:
                break
            try:
                arm.move_to(joints)
            except (TimeoutError, ValueError) as error:
                log.warning("side look not reached (%s)", error)
                break
            current = joints
            look = arm.capture()
            looks.append(look)
            taken += 1
            if not cut_sides(look)[side]:
                break
        if current != home:
            arm.move_to(home)
        if taken:
            notes.append(
                f"{taken} side look(s) {math.degrees(sign * step):+.0f} deg apart: the object "
                "runs past the HOME view's " + ("left" if side == 0 else "right") + " edge"
            )
    return looks, notes


def capture_scan(
    arm: ScanningArm,
    views: Sequence[Sequence[float]],
    cancel: threading.Event | None,
    cancelled: type[Exception] = PerceptionError,
    look_sideways: bool = True,
) -> ScanCapture:
    """Frames from ``views`` (from and back to HOME), each checked against the object's
    extent as seen from HOME first (:mod:`bearchair.skills.perception.clearance`); where the
    object runs out of the HOME view, side looks from HOME turned (:func:`side_looks`)
    first, and the extent is what all of them saw."""
    tick = time.perf_counter()
    arm.move_to(HOME_CONFIGURATION)
    motion_s = time.perf_counter() - tick
    tick = time.perf_counter()
    home_frame = arm.capture()
    looks: list[RGBDFrame] = []
    look_notes: list[str] = []
    with ArmClearance() as clearance:
        if look_sideways:
            looks, look_notes = side_looks(arm, home_frame, clearance)
        extent = chair_extent([home_frame, *looks])
        planned = plan_views(views, extent, clearance)
    plan_s = time.perf_counter() - tick
    frames, notes, seconds = capture_planned(arm, planned, cancel, cancelled)
    for note in look_notes + notes:
        log.warning("%s", note)
    return ScanCapture(
        frames,
        looks,
        look_notes + notes,
        {**seconds, "motion": seconds["motion"] + motion_s, "plan": plan_s},
        extent,
    )


def capture_views(
    arm: ScanningArm,
    views: Sequence[Sequence[float]],
    cancel: threading.Event | None,
    cancelled: type[Exception] = PerceptionError,
) -> tuple[list[RGBDFrame], list[str], dict[str, float]]:
    """Frames from ``views`` (from and back to HOME), each checked against the chair's
    extent as seen from HOME first (:mod:`bearchair.skills.perception.clearance`); no side
    looks (the tracking views of a chair already scanned).

    Returns:
        (frames, notes on views skipped or replaced, wall time: ``motion``, ``capture``
        and ``plan`` (the HOME look and the clearance checks)).
    """
    capture = capture_scan(arm, views, cancel, cancelled, look_sideways=False)
    return capture.frames, capture.notes, capture.seconds
