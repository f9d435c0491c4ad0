"""The sitting imagination's choice: the best rotation and the weighted mean sitting
pose from the scored drops (the paper's step 4, with the window and the split vote of
steps 4-5 of :mod:`bearchair.skills.imagination.imagine`)."""

from __future__ import annotations

import math

import numpy as np

from bearchair.core.geometry import SittingPose, transform_points, wrap_angle
from bearchair.skills.imagination.chair_solid import PreparedChair
from bearchair.skills.imagination.drop_parameters import (
    MIN_CORRECT,
    N_ROTATIONS,
    PULL_MIN_RAD,
    WINDOW_HALF_WIDTH,
)
from bearchair.skills.imagination.drop_records import RawDrop
from bearchair.skills.imagination.sam import failed_criteria
from bearchair.skills.results import DropOutcome, ImaginationResult, RotationVote


def choose_sitting_pose(
    prepared: PreparedChair,
    drops: tuple[DropOutcome, ...],
    seconds: dict[str, float],
    raw: list[RawDrop] | None = None,
    window_half_width: int = WINDOW_HALF_WIDTH,
    extra_drops: int = 0,
) -> ImaginationResult:
    """The paper's choice of the best rotation and the weighted mean pose.

    With ``window_half_width`` w > 0, rotations are compared first by the correct
    sittings in the window α_{i-w} .. α_{i+w}, then by their own; the weighted means
    run over the chosen rotation's own correct sittings (``n_correct`` counts them).
    A split vote is resolved over arcs of contested rotations (see the module doc).

    Args:
        prepared: the chair (for g_obb).
        drops: every scored drop (chair frame).
        seconds: timings to carry into the result.
        raw: the unscored drops, used to explain a failure.
        window_half_width: rotations on each side of α_i that vote with it (0: the paper).
        extra_drops: how many of ``drops`` were added to settle a split vote.
    """
    by_rotation = correct_by_rotation(drops)
    if max(len(v) for v in by_rotation.values()) < MIN_CORRECT:
        return ImaginationResult(
            False, None, 0, len(drops), drops, seconds, _failure_reason(drops, raw)
        )
    best, contested, holes = vote_rotations(by_rotation, window_half_width)
    counts = tuple(len(by_rotation[i]) for i in range(N_ROTATIONS))
    others = [i for i in range(N_ROTATIONS) if i != best and counts[i]]
    runner_up = (
        max(others, key=lambda i: (counts[i], -_mean_jl(by_rotation[i]), -i)) if others else None
    )
    share = counts[best] / sum(counts)
    split = extra_drops > 0 or len(contested) > 1 or bool(holes)
    best, chosen, resolved_by = _resolvevote_rotations(
        best, holes, by_rotation, counts, split, window_half_width
    )
    vote = RotationVote(counts, best, runner_up, share, split, resolved_by, extra_drops)
    pose = _weighted_pose(prepared, chosen)
    return ImaginationResult(True, pose, len(chosen), len(drops), drops, seconds, "", vote=vote)


def _resolvevote_rotations(
    best: int,
    holes: list[int],
    by_rotation: dict[int, list[DropOutcome]],
    counts: tuple[int, ...],
    split: bool,
    window_half_width: int,
) -> tuple[int, list[DropOutcome], str]:
    """The rotation a vote settles on, the sittings its pose is averaged over, and what
    decided it ("" for an unsplit vote).

    A hole whose neighbours' sitters turned toward it replaces ``best`` (module doc, 5).
    """
    chosen = by_rotation[best]
    hole = next((h for h in holes if _pulled_toward(h, by_rotation, window_half_width)), None)
    if hole is not None:
        # Both neighbours of a rotation sit, the rotation itself never does, and the
        # sitters dropped beside it turned toward it: its window's sittings give the pose.
        chosen = [
            d
            for offset in range(-window_half_width, window_half_width + 1)
            for d in by_rotation[(hole + offset) % N_ROTATIONS]
        ]
        return hole, chosen, "sitters on either side turning toward a rotation without its own"
    toward = _turned_toward_instead(best, by_rotation, window_half_width)
    if toward != best:
        return (
            toward,
            by_rotation[toward],
            "the paper's vote beside a window centre whose neighbours did not turn toward it",
        )
    if holes:
        return best, chosen, "the chosen rotation (sitters beside the gap did not turn toward it)"
    if not split:
        return best, chosen, ""

    def key(i: int) -> tuple[int, int]:
        window = sum(
            counts[(i + offset) % N_ROTATIONS]
            for offset in range(-window_half_width, window_half_width + 1)
        )
        return window, counts[i]

    tied = any(key(i) == key(best) for i in range(N_ROTATIONS) if i != best and counts[i])
    return best, chosen, "mean J + L (the paper's tie-break)" if tied else "the window vote"


def _weighted_pose(prepared: PreparedChair, chosen: list[DropOutcome]) -> SittingPose:
    """The 1 / (J + L) weighted mean of the chosen sittings, in the mesh frame (p, γ)."""
    weights = np.array([1.0 / max(_jl(d), 1e-6) for d in chosen])
    position_chair = (weights[:, None] * np.array([d.position for d in chosen])).sum(
        0
    ) / weights.sum()
    yaw_chair = math.atan2(
        float(np.sum(weights * np.sin([d.yaw for d in chosen]))),
        float(np.sum(weights * np.cos([d.yaw for d in chosen]))),
    )
    T_mesh_obb = np.linalg.inv(prepared.T_obb_mesh)
    position = transform_points(T_mesh_obb, position_chair[None, :])[0]
    return SittingPose(position, wrap_angle(yaw_chair - prepared.gamma_obb_rad))


def correct_by_rotation(drops: tuple[DropOutcome, ...]) -> dict[int, list[DropOutcome]]:
    """The correct sittings of each rotation index (0..N_ROTATIONS-1)."""
    by_rotation: dict[int, list[DropOutcome]] = {i: [] for i in range(N_ROTATIONS)}
    for drop in drops:
        if drop.correct:
            by_rotation[drop.rotation_index].append(drop)
    return by_rotation


def _mean_jl(chosen: list[DropOutcome]) -> float:
    return float(np.mean([_jl(d) for d in chosen])) if chosen else math.inf


def vote_rotations(
    by_rotation: dict[int, list[DropOutcome]], window_half_width: int
) -> tuple[int, list[int], list[int]]:
    """The best rotation, the contested ones (itself first) and the holes.

    The paper: most correct sittings, ties to the lowest mean J + L. With a window, the
    neighbouring rotations (±45 degrees) vote too, among the rotations that have a
    correct sitting of their own; the centre still breaks ties. Contested: another
    rotation with as many correct sittings of its own as the best (windows alone tie
    whenever the sittings fall in two adjacent rotations). Holes: rotations without a
    correct sitting of their own whose window holds more than the best's, best first."""

    def window(centre: int) -> int:
        return sum(
            len(by_rotation[(centre + offset) % N_ROTATIONS])
            for offset in range(-window_half_width, window_half_width + 1)
        )

    candidates = [i for i in by_rotation if by_rotation[i]]
    best = min(
        candidates,
        key=lambda i: (
            -window(i),
            -len(by_rotation[i]),
            _mean_jl(by_rotation[i]),
            i,
        ),
    )
    contested = [best] + [
        i for i in candidates if i != best and len(by_rotation[i]) >= len(by_rotation[best])
    ]
    holes = sorted(
        (i for i in by_rotation if not by_rotation[i] and window(i) > window(best)),
        key=lambda i: (-window(i), i),
    )
    return best, contested, holes


def _turned_toward_instead(
    centre: int, by_rotation: dict[int, list[DropOutcome]], window_half_width: int
) -> int:
    """The window's centre, or the rotation beside it the sitters chose instead.

    The window counts the sittings of the rotations beside α_c as votes for α_c; they
    are votes only where those sitters turned toward α_c (:func:`_pulled_toward`). When
    they did not (on a scan with a hole along an armrest, sitters dropped sideways sit
    sideways), a rotation beside α_c replaces it if it wins the paper's own comparison
    (more correct sittings, then the lower mean J + L) and its own neighbours' sitters
    turned toward it; among several, the paper's comparison again.
    """
    if window_half_width == 0 or _pulled_toward(centre, by_rotation, window_half_width):
        return centre

    def paper_key(i: int) -> tuple[int, float, int]:
        return (-len(by_rotation[i]), _mean_jl(by_rotation[i]), i)

    beside = [
        (centre + offset) % N_ROTATIONS
        for offset in range(-window_half_width, window_half_width + 1)
        if offset != 0
    ]
    instead = [
        i
        for i in beside
        if by_rotation[i]
        and paper_key(i) < paper_key(centre)
        and _pulled_toward(i, by_rotation, window_half_width)
    ]
    return min(instead, key=paper_key) if instead else centre


def _pulled_toward(
    target: int, by_rotation: dict[int, list[DropOutcome]], window_half_width: int
) -> bool:
    """True when the sittings in the target's window turned, on their 1 / (J + L) weighted
    mean, more than ``PULL_MIN_RAD`` from the way they were dropped toward the target's
    direction (in the chair frame, where rotation i drops the agent facing −iπ/4)."""
    progress, weights = [], []
    for offset in range(-window_half_width, window_half_width + 1):
        if offset == 0:
            continue
        rotation = (target + offset) % N_ROTATIONS
        for drop in by_rotation[rotation]:
            # Dropped facing −rotation·π/4; the target lies at +offset·π/4 from there.
            turned = wrap_angle(drop.yaw + rotation * math.pi / 4.0)
            progress.append(math.copysign(1.0, offset) * turned)
            weights.append(1.0 / max(_jl(drop), 1e-6))
    return bool(weights) and float(np.average(progress, weights=weights)) > PULL_MIN_RAD


def _jl(drop: DropOutcome) -> float:
    return drop.joint_score + drop.link_score


def _failure_reason(drops: tuple[DropOutcome, ...], raw: list[RawDrop] | None) -> str:
    if not drops:
        return "no drop was simulated"
    reason = f"no correct sitting in {len(drops)} drops"
    if raw:
        counts: dict[str, int] = {}
        for drop in raw:
            for label in failed_criteria(drop):
                counts[label] = counts.get(label, 0) + 1
        common = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:3]
        if common:
            reason += ": " + ", ".join(f"{label} in {n}" for label, n in common)
    return reason + " (not a chair for a child-sized sitter)"
