"""Sitting imagination: drop the agent on the chair and read the sitting pose off the drops.

The paper's procedure ("Sitting Imagination"):

1. Prepare the chair: g_obb (yaw-only OBB alignment and horizontal centring), the solid
   under its surface as boxes, mass properties (``bearchair.skills.imagination.chair_solid``).
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
   that remains goes to the paper's lowest mean J + L, which picked the front in every
   tie measured (docs/decisions.md, "the imagination's tie-break"). A window centre
   whose neighbours' sitters did not turn toward it (they sat as dropped: sideways
   through a scan's hole along an armrest) gives way to the rotation beside it that
   wins the paper's own vote (more correct sittings, then the lower mean J + L) and
   whose neighbours' sitters did turn toward it.

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
import threading
import time
from typing import NamedTuple

import numpy as np
import trimesh

from bearchair.core.geometry import wrap_angle
from bearchair.skills.imagination import DEFAULT_WORKERS
from bearchair.skills.imagination.agent import LINKS, agent_urdf_path
from bearchair.skills.imagination.backrest import check_direction
from bearchair.skills.imagination.chair_solid import (
    ChairPreparationError,
    PreparedChair,
    horizontal_area_m2,
    prepare_chair,
)
from bearchair.skills.imagination.drop_parameters import (
    EXTRA_POSITIONS,
    FIRST_POSITIONS,
    JITTER_POSITION_M,
    JITTER_YAW_RAD,
    L_SIT_RATIO,
    MIN_CORRECT,
    MORE_POSITIONS_MAX_CORRECT,
    N_ROTATIONS,
    SPLIT_SETTLE_REPEATS,
    WINDOW_HALF_WIDTH,
)
from bearchair.skills.imagination.drop_records import (
    ChairBody,
    DropSpec,
    RawDrop,
    SimulationSettings,
    TaskSpec,
)
from bearchair.skills.imagination.sam import (
    DEFAULT_THRESHOLDS,
    SamThresholds,
    score_drop,
)
from bearchair.skills.imagination.simulation import _pybullet
from bearchair.skills.imagination.vote import (
    choose_sitting_pose,
    correct_by_rotation,
    vote_rotations,
)
from bearchair.skills.imagination.workers import Runner, runner, warm_up
from bearchair.skills.results import ImaginationResult


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
        warm_up(workers, wait=False)  # they start up (0.2 s or more) while the chair is prepared
    try:
        prepared = prepare_chair(chair_mesh)
    except ChairPreparationError as error:
        return _not_simulated(error, started)
    drops = _Drops(prepared, seed, settings, runner(workers), cancel)
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
        runner: Runner,
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
    by_rotation = correct_by_rotation(tuple(score_drop(d, thresholds) for d in drops.raw))
    if max(len(v) for v in by_rotation.values()) < MIN_CORRECT:
        return 0
    _, contested, holes = vote_rotations(by_rotation, WINDOW_HALF_WIDTH)
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
