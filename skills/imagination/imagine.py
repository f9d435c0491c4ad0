"""Sitting imagination: drop the agent on the chair and read the sitting pose off the drops.

The paper's procedure ("Sitting Imagination"):

1. Prepare the chair: g_obb (yaw-only OBB alignment and horizontal centring), the solid
   under its surface as boxes, mass properties (``bearchair.skills.imagination.chair``).
2. For each rotation α_i = iπ/4 (i = 0..7) drop the agent in its pre-sitting posture,
   facing +x, with the pelvis 15 cm above the OBB, at the OBB centre and at ±L_sit
   along x; if at most one correct sitting was found, drop again at ±2 L_sit and
   ±3 L_sit: 24 or 56 drops. Rotating the chair by α_i under an agent facing +x is the
   same as turning the agent by −α_i over the fixed chair (gravity is along z), which
   is what is simulated, so every drop is measured directly in the chair frame.
3. Score every drop with the sitting affordance model (``bearchair.skills.imagination.sam``).
4. The best rotation α* has the most correct sittings, ties going to the lowest mean
   J + L. With weights w = 1 / (J + L) over its correct sittings,

       p' = Σ w p / Σ w,   γ' = atan2(Σ w sin γ, Σ w cos γ)   (a circular mean),

   and the sitting pose in the mesh frame is p = g_obb⁻¹ ∘ p', γ = γ' − γ_obb.

5. A split vote: another rotation has as many correct sittings of its own as the chosen
   one (contested), or a rotation without a correct sitting of its own has more in its
   window than the chosen one (a hole: the sitter fails facing it, yet sits turned 45
   degrees to either side). On round or near-symmetric seats the diagonals sit as well
   as the front, and the front itself may fail where the drop lands on an edge. Where
   the votes disagree, every contested rotation and hole is dropped on again
   (``SPLIT_SETTLE_REPEATS`` times at the first three positions, fresh jitter) and the
   vote is taken again over all drops. A hole that remains takes the pose from the
   sittings in its window, the agents on either side having turned toward it; a tie
   that remains goes to the paper's lowest mean J + L. (Measured on the calibration
   chairs' saved drops, 54 fronted meshes: where two or three adjacent rotations tie,
   the rotation of lowest mean J + L was the front in all 13 cases, the lowest mean
   sitting height in 12 and the most backrest contact points in fewer, while averaging
   over the tied rotations put the pose 5-11 degrees off; so the tie-break stays the
   paper's. The one chair the vote got 50 degrees wrong was a hole.)

6. Beyond the paper, a seat without a backrest (a stool, a bench): when no drop of
   steps 2-5 is a correct sitting, the sitter leaning back has found nothing to lean
   on, so upright sitters, which hold their torso upright and balance with a bounded
   righting torque, are dropped at the first three positions of every rotation, and
   the vote of step 4 runs over them, if the chair has horizontal tops at sitting
   height at least as large as the pelvis's footprint (a table's top is too high).

7. Beyond the paper, the direction checked against the chair's shape: the backrest's
   direction (``bearchair.skills.imagination.backrest``: from the centroid of what rises above
   the seat to the seat's centroid) replaces the imagined one when the two disagree by
   more than 30 degrees (a vote one rotation off on a round seat).

Drops run in worker processes (each with its own pybullet DIRECT client), grouped one
rotation per physics world. Each drop's small start jitter is seeded from
(seed, rotation, position), so a seed gives the same result for any number of workers.
"""

from __future__ import annotations

import math
import multiprocessing
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from multiprocessing.process import BaseProcess
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.geometry import SittingPose, transform_points, wrap_angle
from bearchair.core.progress import report as report_progress
from bearchair.core.runtime import RUNTIME
from bearchair.skills.imagination import DEFAULT_WORKERS
from bearchair.skills.imagination.agent import LINKS, agent_urdf_path
from bearchair.skills.imagination.backrest import check_direction
from bearchair.skills.imagination.chair import (
    ChairPreparationError,
    PreparedChair,
    horizontal_area_m2,
    prepare_chair,
)
from bearchair.skills.imagination.sam import (
    DEFAULT_THRESHOLDS,
    SamThresholds,
    failed_criteria,
    score_drop,
)
from bearchair.skills.imagination.simulation import (
    ChairBody,
    DropSpec,
    RawDrop,
    SimulationSettings,
    TaskSpec,
    _pybullet,
    ping,
    run_task,
    worker_initializer,
)
from bearchair.skills.results import DropOutcome, ImaginationResult, RotationVote

_Runner = Callable[
    [list[TaskSpec], threading.Event | None], tuple[list[list[RawDrop]], float, bool]
]
"""Runs tasks until cancelled: (the drops per task run, physics seconds, cancelled)."""

N_ROTATIONS = 8
FIRST_POSITIONS = (0, -1, 1)
EXTRA_POSITIONS = (-2, 2, -3, 3)
L_SIT_RATIO = 0.15
"""L_sit = L_SIT_RATIO × the OBB's mean horizontal side (metres)."""
JITTER_POSITION_M = 0.005
JITTER_YAW_RAD = math.radians(2.0)
WINDOW_HALF_WIDTH = 1
"""Beyond the paper: the rotations at ±45 degrees of α_i vote with it when the best
rotation is chosen (see ``choose_sitting_pose``); the pose is still averaged over the
chosen rotation's own sittings. On round or wide seats the diagonal rotations also give
correct sittings and the paper's tie-break by mean J + L then picks a diagonal; the vote
keeps the rotation whose neighbours agree. Measured on the calibration chairs scanned in
the simulated world (solid collision bodies): the paper's rule put 89 % of the true
meshes within 30 degrees of the front, the vote with a three-rotation mean 93 % but only
74 % of scans within 15 degrees of their true mesh, the vote with the centre's mean 91 %
and 85 %."""
SPLIT_SETTLE_REPEATS = 1
"""A split vote (below) is settled by dropping again, this many more times, at the first
three positions of every contested rotation, with fresh start jitter."""
PULL_MIN_RAD = 2.0 * JITTER_YAW_RAD
"""A sitter turned further than twice the start jitter toward a direction was turned by
the chair, not by how it was dropped."""
MORE_POSITIONS_MAX_CORRECT = 1
"""The paper: the four extra drop positions run when at most this many of the first 24
drops were correct sittings."""
MIN_CORRECT = 1
"""Correct sittings the best rotation needs for a sitting pose to be reported."""


class ImaginationDetails(NamedTuple):
    """The result together with what the benchmark needs.

    Attributes:
        result: what ``imagine_sitting`` returns.
        raw_drops: the unscored simulation outcomes, in drop order.
        steps: physics steps over all drops.
        physics_seconds: wall time spent stepping physics, summed over workers.
        prepared: the chair after preparation.
    """

    result: ImaginationResult
    raw_drops: tuple[RawDrop, ...]
    steps: int
    physics_seconds: float
    prepared: PreparedChair | None


def imagine_sitting(
    chair_mesh: trimesh.Trimesh,
    *,
    seed: int,
    cancel: threading.Event | None = None,
    workers: int = DEFAULT_WORKERS,
    settings: SimulationSettings | None = None,
) -> ImaginationResult:
    """Finds how to sit on a chair by simulating drops of a child-sized agent.

    Args:
        chair_mesh: the chair, z up, metres (the floor at its lowest point), in any frame
            whose z axis is vertical; usually the world frame.
        seed: seeds the drops' start jitter; the same seed gives the same result.
        cancel: when set, pending drops are abandoned and the result says "cancelled".
        workers: worker processes (1 runs in this process).
        settings: the drops' physics and stopping (default: :class:`SimulationSettings`).

    Returns:
        The sitting pose g = (p, γ) in the mesh's frame, every drop, and the timings;
        or ``found=False`` with the reason (not a chair, degenerate mesh, cancelled).
    """
    return imagine_sitting_details(
        chair_mesh, seed=seed, cancel=cancel, workers=workers, settings=settings
    ).result


def imagine_sitting_details(
    chair_mesh: trimesh.Trimesh,
    *,
    seed: int,
    cancel: threading.Event | None = None,
    workers: int = DEFAULT_WORKERS,
    thresholds: SamThresholds = DEFAULT_THRESHOLDS,
    settings: SimulationSettings | None = None,
) -> ImaginationDetails:
    """``imagine_sitting`` with the raw drops and physics statistics (for benchmarks)."""
    settings = settings or SimulationSettings()
    started = time.perf_counter()
    _pybullet()  # imported quietly here, before anything else imports it with its banner
    if workers > 1:
        _pool(workers)  # the workers start up (0.2 s or more) while the chair is prepared
    try:
        prepared = prepare_chair(chair_mesh)
    except ChairPreparationError as error:
        return _not_simulated(error, started)
    drops = _Drops(prepared, seed, settings, _runner(workers), cancel)
    prepared_at = time.perf_counter()

    n_correct = _drop_leaning_back(drops, thresholds)
    upright = False
    if not drops.cancelled and n_correct == 0 and _offers_seat(prepared, thresholds):
        # No sitter leaning back found a backrest: is it a seat without one (a stool,
        # a bench)? Drop upright sitters, which balance instead of leaning back.
        upright = True
        drops.run([drops.task(i, FIRST_POSITIONS, upright=True) for i in range(N_ROTATIONS)])
    extra = 0
    if not drops.cancelled:
        extra = _settle_split_vote(drops, thresholds, upright)
    simulated_at = time.perf_counter()

    raw = drops.raw
    raw.sort(
        key=lambda d: (
            d.spec.upright,
            d.spec.rotation_index,
            d.spec.repeat,
            _position_order(d.spec.position_index),
        )
    )
    seconds = {
        "prepare": prepared_at - started,
        "simulate": simulated_at - prepared_at,
        "total": simulated_at - started,
    }
    result = _imagined(chair_mesh, prepared, raw, drops.cancelled, extra, seconds, thresholds, seed)
    steps = sum(drop.steps for drop in raw)
    return ImaginationDetails(result, tuple(raw), steps, drops.physics_seconds, prepared)


def _not_simulated(error: ChairPreparationError, started: float) -> ImaginationDetails:
    """The details of a chair that could not be prepared (``started``: perf_counter s)."""
    total = time.perf_counter() - started
    result = ImaginationResult(
        False,
        None,
        0,
        0,
        (),
        {"prepare": total, "simulate": 0.0, "total": total},
        f"not simulated: {error}",
    )
    return ImaginationDetails(result, (), 0, 0.0, None)


class _Drops:
    """The drops of one imagination: their tasks, run by ``runner``, and what came back.

    Attributes:
        raw: every drop simulated so far, in the order the tasks returned them.
        physics_seconds: wall time spent stepping physics, summed over the runs.
        cancelled: whether the last run was cancelled.
    """

    def __init__(
        self,
        prepared: PreparedChair,
        seed: int,
        settings: SimulationSettings,
        runner: _Runner,
        cancel: threading.Event | None,
    ) -> None:
        self._prepared = prepared
        self._seed = seed
        self._settings = settings
        self._urdf = str(agent_urdf_path())
        self._body = ChairBody.of(prepared)
        self._runner = runner
        self._cancel = cancel
        self.raw: list[RawDrop] = []
        self.physics_seconds = 0.0
        self.cancelled = False

    def task(
        self,
        rotation_index: int,
        positions: tuple[int, ...],
        repeat: int = 0,
        upright: bool = False,
    ) -> TaskSpec:
        """The drops of one rotation as one task (see ``_drop_specs``)."""
        specs = _drop_specs(
            self._prepared, rotation_index, positions, self._seed, repeat=repeat, upright=upright
        )
        return TaskSpec(self._body, self._urdf, specs, self._settings)

    def run(self, tasks: list[TaskSpec]) -> list[RawDrop]:
        """Runs the tasks (until cancelled); keeps and returns the drops that came back."""
        outcomes, seconds, self.cancelled = self._runner(tasks, self._cancel)
        self.physics_seconds += seconds
        more = [drop for task_drops in outcomes for drop in task_drops]
        self.raw.extend(more)
        return more


def _drop_leaning_back(drops: _Drops, thresholds: SamThresholds) -> int:
    """The paper's drops: the first positions of every rotation, then the extra positions
    if at most ``MORE_POSITIONS_MAX_CORRECT`` were correct sittings.

    Returns:
        The correct sittings among the drops so far (0 when cancelled first).
    """
    n_correct = 0
    for positions in (FIRST_POSITIONS, EXTRA_POSITIONS):
        drops.run([drops.task(i, positions) for i in range(N_ROTATIONS)])
        if drops.cancelled:
            break
        n_correct = sum(score_drop(drop, thresholds).correct for drop in drops.raw)
        if n_correct > MORE_POSITIONS_MAX_CORRECT:
            break
    return n_correct


def _settle_split_vote(drops: _Drops, thresholds: SamThresholds, upright: bool) -> int:
    """A split vote: drops again at every contested rotation and hole (module doc, 5).

    Returns:
        How many drops were added (0 when the vote is not split).
    """
    by_rotation = _correct_by_rotation(tuple(score_drop(d, thresholds) for d in drops.raw))
    if max(len(v) for v in by_rotation.values()) < MIN_CORRECT:
        return 0
    _, contested, holes = _vote(by_rotation, WINDOW_HALF_WIDTH)
    if not (len(contested) > 1 or holes):
        return 0
    tasks = [
        drops.task(i, FIRST_POSITIONS, repeat=repeat, upright=upright)
        for i in sorted(set(contested) | set(holes))
        for repeat in range(1, SPLIT_SETTLE_REPEATS + 1)
    ]
    return len(drops.run(tasks))


def _imagined(
    chair_mesh: trimesh.Trimesh,
    prepared: PreparedChair,
    raw: list[RawDrop],
    cancelled: bool,
    extra_drops: int,
    seconds: dict[str, float],
    thresholds: SamThresholds,
    seed: int,
) -> ImaginationResult:
    """The result from the sorted raw drops: scored, voted on, the direction checked."""
    drops = tuple(score_drop(drop, thresholds) for drop in raw)
    if cancelled:
        result = ImaginationResult(False, None, 0, len(drops), drops, seconds, "cancelled")
    else:
        result = choose_sitting_pose(prepared, drops, seconds, raw, extra_drops=extra_drops)
    result = result._replace(T_mesh_chair=np.linalg.inv(prepared.T_obb_mesh))
    if result.sitting_pose is not None:
        sitting_pose, backrest = check_direction(chair_mesh, result.sitting_pose, seed=seed)
        result = result._replace(sitting_pose=sitting_pose, backrest=backrest)
    return result


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
    by_rotation = _correct_by_rotation(drops)
    if max(len(v) for v in by_rotation.values()) < MIN_CORRECT:
        return ImaginationResult(
            False, None, 0, len(drops), drops, seconds, _failure_reason(drops, raw)
        )
    best, contested, holes = _vote(by_rotation, window_half_width)
    counts = tuple(len(by_rotation[i]) for i in range(N_ROTATIONS))
    others = [i for i in range(N_ROTATIONS) if i != best and counts[i]]
    runner_up = (
        max(others, key=lambda i: (counts[i], -_mean_jl(by_rotation[i]), -i)) if others else None
    )
    share = counts[best] / sum(counts)
    split = extra_drops > 0 or len(contested) > 1 or bool(holes)
    best, chosen, resolved_by = _resolve_vote(
        best, holes, by_rotation, counts, split, window_half_width
    )
    vote = RotationVote(counts, best, runner_up, share, split, resolved_by, extra_drops)
    pose = _weighted_pose(prepared, chosen)
    return ImaginationResult(True, pose, len(chosen), len(drops), drops, seconds, "", vote=vote)


def _resolve_vote(
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


def _offers_seat(prepared: PreparedChair, thresholds: SamThresholds) -> bool:
    """True when the chair has horizontal tops where a pelvis would rest within the
    sitting heights (H_min..H_max less the pelvis's half height), at least as large as
    the pelvis's footprint: an upright sitter could sit there. A table's top is above."""
    pelvis = LINKS[0]
    half_height_m = pelvis.size[2] / 2.0
    area_m2 = horizontal_area_m2(
        prepared,
        thresholds.height_min_m - half_height_m,
        thresholds.height_max_m - half_height_m,
    )
    return area_m2 >= pelvis.size[0] * pelvis.size[1]


def _correct_by_rotation(drops: tuple[DropOutcome, ...]) -> dict[int, list[DropOutcome]]:
    by_rotation: dict[int, list[DropOutcome]] = {i: [] for i in range(N_ROTATIONS)}
    for drop in drops:
        if drop.correct:
            by_rotation[drop.rotation_index].append(drop)
    return by_rotation


def _mean_jl(chosen: list[DropOutcome]) -> float:
    return float(np.mean([_jl(d) for d in chosen])) if chosen else math.inf


def _vote(
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


def _pulled_toward(
    hole: int, by_rotation: dict[int, list[DropOutcome]], window_half_width: int
) -> bool:
    """True when the sittings in the hole's window turned, on their 1 / (J + L) weighted
    mean, more than ``PULL_MIN_RAD`` from the way they were dropped toward the hole's
    direction (in the chair frame, where rotation i drops the agent facing −iπ/4)."""
    progress, weights = [], []
    for offset in range(-window_half_width, window_half_width + 1):
        if offset == 0:
            continue
        rotation = (hole + offset) % N_ROTATIONS
        for drop in by_rotation[rotation]:
            # Dropped facing −rotation·π/4; the hole lies at +offset·π/4 from there.
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


def _position_order(k: int) -> int:
    return abs(k) * 2 + (1 if k > 0 else 0)


def _drop_specs(
    prepared: PreparedChair,
    rotation_index: int,
    positions: tuple[int, ...],
    seed: int,
    repeat: int = 0,
    upright: bool = False,
) -> tuple[DropSpec, ...]:
    """The drops of one rotation: the agent faces −α_i in the chair frame.

    ``repeat`` > 0 draws fresh start jitter for drops repeated to settle a split vote;
    ``upright`` drops an upright sitter (no backrest to lean on)."""
    l_sit = L_SIT_RATIO * float(np.mean(prepared.extents_m[:2]))
    specs = []
    for k in positions:
        key = [seed & 0xFFFFFFFF, rotation_index, k + 16] + ([repeat] if repeat else [])
        rng = np.random.default_rng(key)
        yaw = wrap_angle(-rotation_index * math.pi / 4.0 + rng.uniform(-1, 1) * JITTER_YAW_RAD)
        facing = np.array(
            [math.cos(-rotation_index * math.pi / 4.0), math.sin(-rotation_index * math.pi / 4.0)]
        )
        xy = k * l_sit * facing + rng.uniform(-1, 1, size=2) * JITTER_POSITION_M
        specs.append(
            DropSpec(
                rotation_index, k, k * l_sit, (float(xy[0]), float(xy[1])), yaw, repeat, upright
            )
        )
    return tuple(specs)


_pools: dict[int, ProcessPoolExecutor] = {}
"""One pool per worker count asked for (in practice one: ``DEFAULT_WORKERS``)."""
_pools_lock = threading.Lock()


def _runner(workers: int) -> _Runner:
    """The same tasks, in this process or in a pool of worker processes."""
    if workers <= 1:
        return _run_here
    return lambda tasks, cancel: _run_in_pool(_pool(workers), tasks, cancel)


def _run_here(
    tasks: list[TaskSpec], cancel: threading.Event | None
) -> tuple[list[list[RawDrop]], float, bool]:
    outcomes, seconds = [], 0.0
    total = sum(len(task.drops) for task in tasks)
    for task in tasks:
        _report_drops(outcomes, total)
        if cancel is not None and cancel.is_set():
            return outcomes, seconds, True
        drops, task_seconds = run_task(task)
        outcomes.append(drops)
        seconds += task_seconds
    _report_drops(outcomes, total)
    return outcomes, seconds, False


def _report_drops(outcomes: list[list[RawDrop]], total: int) -> None:
    """The drops of this batch simulated so far, for a console's progress bar."""
    report_progress("imagination: drops", sum(len(drops) for drops in outcomes), total)


def _run_in_pool(
    pool: ProcessPoolExecutor, tasks: list[TaskSpec], cancel: threading.Event | None
) -> tuple[list[list[RawDrop]], float, bool]:
    futures: list[Future] = [pool.submit(run_task, task) for task in tasks]
    pending = set(futures)
    total = sum(len(task.drops) for task in tasks)
    while pending:
        _, pending = wait(pending, timeout=0.05, return_when=FIRST_COMPLETED)
        report_progress(
            "imagination: drops",
            sum(len(task.drops) for task, f in zip(tasks, futures, strict=True) if f.done()),
            total,
        )
        if cancel is not None and cancel.is_set():
            for future in pending:
                future.cancel()
            done = [f.result() for f in futures if f.done() and not f.cancelled()]
            return [d for d, _ in done], sum(s for _, s in done), True
    results = [future.result() for future in futures]
    return [drops for drops, _ in results], sum(seconds for _, seconds in results), False


_pings: dict[int, list[Future]] = {}
"""Each pool's start-up no-ops (one per worker), as many pools as ``_pools``."""


def _pool(workers: int) -> ProcessPoolExecutor:
    """A persistent pool per worker count: process start-up is paid once per process.

    A new pool is sent one no-op per worker, so every worker process starts at once
    (the pool starts one per task submitted) and the caller need not wait for them."""
    with _pools_lock:
        pool = _pools.get(workers)
        if pool is None:
            pool = ProcessPoolExecutor(
                max_workers=workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=worker_initializer,
            )
            _pools[workers] = pool
            _pings[workers] = [pool.submit(ping) for _ in range(workers)]
        return pool


def warm_up(workers: int = DEFAULT_WORKERS, *, wait: bool = True) -> None:
    """Starts the worker processes now (they import pybullet and connect).

    Args:
        workers: the worker count a later ``imagine_sitting`` will use.
        wait: return only once every worker is up; else start them and return.
    """
    if workers > 1:
        _pool(workers)
        if wait:
            for future in _pings[workers]:
                future.result()


def shutdown_workers(timeout_s: float = 30.0) -> bool:
    """Stops the worker processes: each ends after its current task; those still running
    after ``timeout_s`` are killed. Returns True when none had to be killed.

    The runtime's shutdown (``bearchair.core.runtime``) calls it, at the latest at exit."""
    with _pools_lock:
        pools = list(_pools.values())
        _pings.clear()
    workers = [process for pool in pools for process in _worker_processes(pool)]
    for pool in pools:
        pool.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + timeout_s
    for process in workers:
        process.join(max(deadline - time.monotonic(), 0.0))
    late = [process for process in workers if process.is_alive()]
    for process in late:
        process.kill()
        process.join(5.0)
    with _pools_lock:  # only now: a second stop signal meanwhile still finds them
        for workers_asked, pool in list(_pools.items()):
            if pool in pools:
                del _pools[workers_asked]
    # The executor's manager thread holds the pool's queues, whose named semaphores
    # unregister from the resource tracker when they are collected; joined here, the
    # queues go now, not after the tracker has stopped (which would start a new one).
    for pool in pools:
        manager = getattr(pool, "_executor_manager_thread", None)  # private field
        if manager is not None:
            manager.join(max(deadline - time.monotonic(), 0.0))
    return not late


def kill_workers() -> None:
    """SIGKILLs the worker processes now and reaps them (a second stop signal).

    Takes no lock: it runs in a signal handler, perhaps while this thread holds one."""
    pools = list(_pools.values())
    _pools.clear()  # broken now: the next imagination starts a new pool
    _pings.clear()
    workers = [process for pool in pools for process in _worker_processes(pool)]
    for process in workers:
        process.kill()
    for process in workers:
        process.join(2.0)


def _worker_processes(pool: ProcessPoolExecutor) -> list[BaseProcess]:
    """The pool's worker processes (the executor keeps them by pid, in a private field)."""
    return list((getattr(pool, "_processes", None) or {}).values())


RUNTIME.register("imagination pool", shutdown=shutdown_workers, kill=kill_workers)
