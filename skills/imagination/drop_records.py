"""What the drops are told and what they give back: the simulation's settings, one drop,
the chair body a worker builds, a task of drops, and a drop's raw outcome.

Plain records, cheap to import and to send to the worker processes
(:mod:`bearchair.skills.imagination.workers`); the simulation that fills them is
:mod:`bearchair.skills.imagination.simulation`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from bearchair.skills.imagination.chair_solid import PreparedChair


class SimulationSettings(NamedTuple):
    """Physics and stopping parameters (seconds, metres, radians).

    Attributes:
        time_step_s: physics step.
        solver_iterations: constraint solver iterations per step.
        max_time_s: simulated time after which a drop is stopped anyway.
        min_time_s: no rest test before this (the agent is still falling).
        check_every_steps: steps between two rest tests.
        rest_checks: consecutive rest tests needed.
        rest_linear_mps: pelvis speed below which the agent may be at rest.
        rest_angular_rps: pelvis angular speed limit at rest.
        rest_joint_rps: joint speed limit at rest.
        give_up_height_m: a pelvis lower than this above the floor cannot sit.
        drop_clearance_m: the pelvis starts this far above the OBB top (the paper: 15 cm).
        chair_friction: lateral friction of chair and agent.
        dynamic_chair: the chair has its mass (it may slide or tip), else it is fixed.
    """

    time_step_s: float = 1.0 / 120.0
    solver_iterations: int = 20
    max_time_s: float = 2.5
    min_time_s: float = 0.35
    check_every_steps: int = 4
    rest_checks: int = 3
    rest_linear_mps: float = 0.04
    rest_angular_rps: float = 0.3
    rest_joint_rps: float = 0.5
    give_up_height_m: float = 0.08
    drop_clearance_m: float = 0.15
    chair_friction: float = 0.8
    dynamic_chair: bool = True


class DropSpec(NamedTuple):
    """Where and how one agent is dropped (chair frame).

    Attributes:
        rotation_index: i of α_i = iπ/4 (the agent faces -α_i in the chair frame,
            which is the paper's chair rotated by α_i under an agent facing +x).
        position_index: k, the drop is k * L_sit along the agent's facing direction.
        offset_m: k * L_sit.
        xy_m: (2,) pelvis start position in the chair frame.
        yaw_rad: agent start yaw in the chair frame.
        repeat: 0 for the paper's drops, 1.. for drops repeated to settle a split vote.
        upright: an upright sitter (beyond the paper): the torso held upright and a
            bounded righting torque on the pelvis (``agent.BALANCE_TORQUE_MAX_NM``),
            as a child balances on a seat without a backrest.
    """

    rotation_index: int
    position_index: int
    offset_m: float
    xy_m: tuple[float, float]
    yaw_rad: float
    repeat: int = 0
    upright: bool = False


class ChairBody(NamedTuple):
    """What a drop needs of a ``PreparedChair`` (same fields, same units).

    Sent to the worker processes instead of the prepared chair: its boxes stay behind,
    and the workers need not import the mesh libraries (trimesh, scipy), about half a
    second of each worker's start-up.
    """

    collision_obj: str
    support_obj: str
    extents_m: np.ndarray
    z_min_m: float
    z_top_m: float
    com_obb_m: np.ndarray
    mass_kg: float
    inertia_diag: np.ndarray

    @classmethod
    def of(cls, prepared: PreparedChair) -> ChairBody:
        """The body of a prepared chair."""
        return cls(*(getattr(prepared, name) for name in cls._fields))


class TaskSpec(NamedTuple):
    """Drops simulated together in one world."""

    chair: ChairBody
    urdf_path: str
    drops: tuple[DropSpec, ...]
    settings: SimulationSettings


class RawDrop(NamedTuple):
    """The agent's final state, in the chair frame (the chair's pose at the end).

    Attributes:
        spec: the drop.
        position: (3,) pelvis position (metres).
        yaw: pelvis heading, from +x about +z (radians).
        joint_angles: (n_joints,) in ``JOINTS`` order (radians).
        link_z: (n_links, 3) each link frame's z axis, in ``LINK_NAMES`` order.
        contacts: (n_links,) contact points of each link with the chair.
        sitting_height_m: pelvis height above the floor.
        steps: physics steps simulated.
        stopped_by: ``rest``, ``fell`` or ``time``.
        link_poses: (n_links, 4, 4) each link's frame T_chair_link, in ``LINK_NAMES``
            order (what a viewer draws; the scores use ``link_z``).
    """

    spec: DropSpec
    position: np.ndarray
    yaw: float
    joint_angles: np.ndarray
    link_z: np.ndarray
    contacts: np.ndarray
    sitting_height_m: float
    steps: int
    stopped_by: str
    link_poses: np.ndarray | None = None
