"""The drops: the agent falls onto the chair in a pybullet DIRECT world.

One *task* is a group of drops simulated together in one physics world: each drop has
its own copy of the chair, spaced apart so they never interact, and one
``stepSimulation`` advances them all. A drop stops (its agent and chair are removed
from the world) as soon as its agent is at rest, or as soon as it cannot end as a
correct sitting any more (the pelvis is below the lowest sitting height, or off the
chair). Only raw measurements come back; the sitting affordance model scores them
(``bearchair.skills.imagination.sam``), so thresholds can be tuned without simulating again.

A task is computed the same way in whichever process runs it, starting from
``resetSimulation``: the result of a seed does not depend on the number of workers.

Each chair copy is its boxes, which the agent touches, and their convex hull, which the
floor touches (``add_chair``).

Frames: the chair frame is the OBB frame of ``PreparedChair`` (after g_obb); chair
copy j stands at T_world_chair_j = translation(0, j * spacing, 0).
"""

from __future__ import annotations

import math
import os
import signal
import time
from typing import Any

import numpy as np

from bearchair.core.geometry import yaw_of
from bearchair.core.streams import silenced_fds
from bearchair.skills.imagination.agent import (
    BALANCE_FULL_TILT_RAD,
    BALANCE_TORQUE_MAX_NM,
    JOINTS,
    LINK_NAMES,
    upright_targets,
)
from bearchair.skills.imagination.drop_records import (
    ChairBody,
    DropSpec,
    RawDrop,
    SimulationSettings,
    TaskSpec,
)

SUPPORT_LINK = 0
"""The chair body's link that touches the floor (its convex hull; the base is the boxes)."""
SUPPORT_MASS_KG = 1e-3
"""Mass of that link (kg): negligible beside a chair's 1.5-12 kg, and not zero, which
pybullet would take for a static link."""

TRUNK_LINKS = ("pelvis", "chest", "head")
"""Links whose contact with the floor ends a drop as fallen."""

_client: dict[str, Any] = {}
"""This process's pybullet module and DIRECT client id: two keys, bounded by design."""


def _pybullet() -> Any:
    """Imports pybullet with its build banner (printed by C code) sent to /dev/null."""
    if "module" not in _client:
        with silenced_fds(1, 2):
            import pybullet
        _client["module"] = pybullet
    return _client["module"]


def _connection() -> tuple[Any, int]:
    """This process's own DIRECT client (one per process)."""
    p = _pybullet()
    if "id" not in _client or not p.isConnected(_client["id"]):
        _client["id"] = p.connect(p.DIRECT)
    return p, _client["id"]


def worker_initializer() -> None:
    """Runs in each worker process: C-level prints must not reach the caller's stdout.

    Ctrl-C reaches every process of the terminal's group: the caller cancels and
    shuts the pool down, so a worker ignores SIGINT instead of printing a traceback.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    _pybullet()
    _connection()


def ping() -> int:
    """A no-op task that starts a worker process (defined here, where the workers import
    nothing they do not need)."""
    return 0


def run_task(task: TaskSpec) -> tuple[list[RawDrop], float]:
    """Simulates a group of drops in a fresh world of this process's client.

    Returns:
        The raw outcomes in the order of ``task.drops`` and the wall time (seconds)
        spent stepping the physics.
    """
    p, cid = _connection()
    floor, chair_shape, support_shape = _reset_world(p, cid, task)
    active = _place_drops(p, cid, task, floor, chair_shape, support_shape)
    return _simulate(p, cid, task, active)


def _reset_world(p: Any, cid: int, task: TaskSpec) -> tuple[int, int, int]:
    """Empties the world and sets its physics; adds the floor and the chair's shapes.

    Returns:
        (floor body id, the chair's boxes' collision shape, their hull's collision shape).
    """
    settings = task.settings
    chair = task.chair
    p.resetSimulation(physicsClientId=cid)
    p.setGravity(0, 0, -9.81, physicsClientId=cid)
    p.setPhysicsEngineParameter(
        fixedTimeStep=settings.time_step_s,
        numSolverIterations=settings.solver_iterations,
        deterministicOverlappingPairs=1,
        physicsClientId=cid,
    )
    floor_shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=cid)
    floor = p.createMultiBody(
        0, floor_shape, basePosition=[0, 0, chair.z_min_m], physicsClientId=cid
    )
    p.changeDynamics(floor, -1, lateralFriction=settings.chair_friction, physicsClientId=cid)
    chair_shape = p.createCollisionShape(
        p.GEOM_MESH, fileName=chair.collision_obj, physicsClientId=cid
    )
    support_shape = p.createCollisionShape(
        p.GEOM_MESH, fileName=chair.support_obj, physicsClientId=cid
    )
    return floor, chair_shape, support_shape


def _place_drops(
    p: Any, cid: int, task: TaskSpec, floor: int, chair_shape: int, support_shape: int
) -> list[dict[str, Any]]:
    """Adds every drop's chair copy and agent, posed and driven, ready to fall.

    Returns:
        One record per drop, in ``task.drops`` order (what ``_stop_reason`` and
        ``_measure`` read).
    """
    settings = task.settings
    chair = task.chair
    spacing = float(max(chair.extents_m[:2])) + 2.5
    agent_joint_indices: list[int] = []
    link_indices: list[int] = []
    torques = [joint.max_torque_nm for joint in JOINTS]

    active: list[dict[str, Any]] = []
    for j, drop in enumerate(task.drops):
        origin = np.array([0.0, j * spacing, 0.0])
        chair_body = add_chair(p, cid, chair, chair_shape, support_shape, floor, origin, settings)
        agent, z, quat = _load_agent(p, cid, task, drop, origin)
        if not agent_joint_indices:
            agent_joint_indices, link_indices = _index_maps(p, cid, agent)
            trunk = {link_indices[LINK_NAMES.index(name)] for name in TRUNK_LINKS}
        # The chair's support hull stands for it on the floor only (see add_chair).
        for link_index in range(-1, p.getNumJoints(agent, physicsClientId=cid)):
            p.setCollisionFilterPair(
                agent, chair_body, link_index, SUPPORT_LINK, 0, physicsClientId=cid
            )
        targets = upright_targets() if drop.upright else [joint.pre_sitting_rad for joint in JOINTS]
        for index, angle in zip(agent_joint_indices, targets, strict=True):
            p.resetJointState(agent, index, angle, physicsClientId=cid)
        _lift_clear_of_chair(p, cid, agent, chair_body, origin, drop, z, quat)
        _drive(p, cid, agent, agent_joint_indices, link_indices, targets, torques, settings)
        active.append(
            {
                "index": j,
                "spec": drop,
                "agent": agent,
                "chair": chair_body,
                "joints": agent_joint_indices,
                "links": link_indices,
                "rest": 0,
                "floor": floor,
                "trunk": trunk,
            }
        )
    return active


def _load_agent(
    p: Any, cid: int, task: TaskSpec, drop: DropSpec, origin: np.ndarray
) -> tuple[int, float, Any]:
    """Loads one drop's agent above its chair copy at ``origin`` (metres, world frame).

    Returns:
        (the agent's body id, its pelvis start height in metres, its start quaternion).
    """
    quat = p.getQuaternionFromEuler([0.0, 0.0, drop.yaw_rad])
    z = task.chair.z_top_m + task.settings.drop_clearance_m
    agent = p.loadURDF(
        task.urdf_path,
        basePosition=[origin[0] + drop.xy_m[0], origin[1] + drop.xy_m[1], z],
        baseOrientation=quat,
        # Cached graphics shapes: the agent's visuals (which a DIRECT world never
        # draws) are built once per world, not per drop: half of loadURDF's 3.5 ms.
        flags=p.URDF_USE_INERTIA_FROM_FILE | p.URDF_ENABLE_CACHED_GRAPHICS_SHAPES,
        physicsClientId=cid,
    )
    return agent, z, quat


def _drive(
    p: Any,
    cid: int,
    agent: int,
    joint_indices: list[int],
    link_indices: list[int],
    targets: list[float],
    torques: list[float],
    settings: SimulationSettings,
) -> None:
    """Gives the agent's links their friction and holds its joints at ``targets``
    (radians) with position motors of at most ``torques`` (N m)."""
    for link_index in link_indices:
        p.changeDynamics(
            agent, link_index, lateralFriction=settings.chair_friction, physicsClientId=cid
        )
    p.setJointMotorControlArray(
        agent,
        joint_indices,
        p.POSITION_CONTROL,
        targetPositions=targets,
        forces=torques,
        physicsClientId=cid,
    )


def _lift_clear_of_chair(
    p: Any,
    cid: int,
    agent: int,
    chair_body: int,
    origin: np.ndarray,
    drop: DropSpec,
    z: float,
    quat: Any,
) -> None:
    """Raises the agent by 5 cm steps (20 at most) from height ``z`` (metres) until it
    starts clear of the chair: the legs hang below the pelvis and would otherwise start
    inside a tall backrest."""
    for _ in range(20):
        if not p.getClosestPoints(agent, chair_body, 0.005, linkIndexB=-1, physicsClientId=cid):
            break
        z += 0.05
        p.resetBasePositionAndOrientation(
            agent,
            [origin[0] + drop.xy_m[0], origin[1] + drop.xy_m[1], z],
            quat,
            physicsClientId=cid,
        )


def _simulate(
    p: Any, cid: int, task: TaskSpec, active: list[dict[str, Any]]
) -> tuple[list[RawDrop], float]:
    """Steps the world until every drop has stopped, measuring and removing each as it
    stops (see ``run_task``)."""
    settings = task.settings
    chair = task.chair
    results: list[RawDrop | None] = [None] * len(task.drops)
    max_steps = math.ceil(settings.max_time_s / settings.time_step_s)
    min_steps = int(settings.min_time_s / settings.time_step_s)
    step = 0
    started = time.perf_counter()
    while active and step < max_steps:
        upright = [item["agent"] for item in active if item["spec"].upright]
        for _ in range(settings.check_every_steps):
            for agent in upright:
                _apply_righting_torque(p, cid, agent)
            p.stepSimulation(physicsClientId=cid)
        step += settings.check_every_steps
        still: list[dict[str, Any]] = []
        for item in active:
            stopped_by = _stop_reason(p, cid, item, chair, settings, step, min_steps)
            if stopped_by is None and step < max_steps:
                still.append(item)
                continue
            results[item["index"]] = _measure(p, cid, item, chair, step, stopped_by or "time")
            p.removeBody(item["agent"], physicsClientId=cid)
            p.removeBody(item["chair"], physicsClientId=cid)
        active = still
    seconds = time.perf_counter() - started
    return [r for r in results if r is not None], seconds


def add_chair(
    p: Any,
    cid: int,
    chair: ChairBody,
    chair_shape: int,
    support_shape: int,
    floor: int,
    origin: np.ndarray,
    settings: SimulationSettings,
) -> int:
    """Adds one copy of the chair, its OBB frame at ``origin`` (metres, world frame).

    The chair's boxes (``chair_shape``, the base) touch the agent; their convex hull
    (``support_shape``, a link fixed to the base) touches the floor. A flat floor meets a
    rigid body only at points of its convex hull, so the chair stands, slides and tips as
    on its boxes, with a few contact points instead of four under every floor-standing
    box: a few hundred boxes made the chair-floor contacts most of a drop's cost.

    Returns:
        The chair's body id.
    """
    chair_body = p.createMultiBody(
        baseMass=chair.mass_kg if settings.dynamic_chair else 0.0,
        baseCollisionShapeIndex=chair_shape,
        basePosition=(origin + chair.com_obb_m).tolist(),
        baseInertialFramePosition=[0, 0, 0],
        linkMasses=[SUPPORT_MASS_KG if settings.dynamic_chair else 0.0],
        linkCollisionShapeIndices=[support_shape],
        linkVisualShapeIndices=[-1],
        linkPositions=[[0, 0, 0]],
        linkOrientations=[[0, 0, 0, 1]],
        linkInertialFramePositions=[[0, 0, 0]],
        linkInertialFrameOrientations=[[0, 0, 0, 1]],
        linkParentIndices=[0],
        linkJointTypes=[p.JOINT_FIXED],
        linkJointAxis=[[0, 0, 1]],
        physicsClientId=cid,
    )
    p.setCollisionFilterPair(chair_body, floor, -1, -1, 0, physicsClientId=cid)
    p.changeDynamics(
        chair_body, SUPPORT_LINK, lateralFriction=settings.chair_friction, physicsClientId=cid
    )
    if settings.dynamic_chair:
        p.changeDynamics(
            chair_body,
            -1,
            localInertiaDiagonal=chair.inertia_diag.tolist(),
            lateralFriction=settings.chair_friction,
            physicsClientId=cid,
        )
    else:
        p.changeDynamics(
            chair_body, -1, lateralFriction=settings.chair_friction, physicsClientId=cid
        )
    return chair_body


def _apply_righting_torque(p: Any, cid: int, agent: int) -> None:
    """An upright sitter's balance: a torque on the pelvis about a horizontal axis that
    turns its z axis back toward vertical, τ = −k θ n − c ω_h (θ the tilt, n the tilt
    axis, ω_h the horizontal angular velocity), saturated at ``BALANCE_TORQUE_MAX_NM``
    (N m), so a sitter whose weight is more than ``BALANCE_LEAN_M`` outside what supports
    it still falls. pybullet clears external forces after every step."""
    _, quat = p.getBasePositionAndOrientation(agent, physicsClientId=cid)
    z_pelvis = np.array(p.getMatrixFromQuaternion(quat)).reshape(3, 3)[:, 2]
    _, angular = p.getBaseVelocity(agent, physicsClientId=cid)
    # z_pelvis × z_world is the axis that rights the pelvis; its norm is sin θ.
    axis = np.array([z_pelvis[1], -z_pelvis[0], 0.0])
    sin_tilt = float(np.linalg.norm(axis))
    tilt = math.atan2(sin_tilt, float(z_pelvis[2]))
    stiffness = BALANCE_TORQUE_MAX_NM / BALANCE_FULL_TILT_RAD
    torque = -0.2 * stiffness * np.array([angular[0], angular[1], 0.0])
    if sin_tilt > 1e-9:
        torque += stiffness * tilt * axis / sin_tilt
    norm = float(np.linalg.norm(torque))
    if norm > BALANCE_TORQUE_MAX_NM:
        torque *= BALANCE_TORQUE_MAX_NM / norm
    p.applyExternalTorque(agent, -1, torque.tolist(), p.WORLD_FRAME, physicsClientId=cid)


def _index_maps(p: Any, cid: int, agent: int) -> tuple[list[int], list[int]]:
    """pybullet's joint indices in ``JOINTS`` order and link indices in ``LINK_NAMES`` order.

    pybullet numbers links in its own traversal order, so names are matched, never assumed.
    """
    joint_by_name: dict[str, int] = {}
    link_by_name: dict[str, int] = {"pelvis": -1}
    for index in range(p.getNumJoints(agent, physicsClientId=cid)):
        info = p.getJointInfo(agent, index, physicsClientId=cid)
        joint_by_name[info[1].decode()] = index
        link_by_name[info[12].decode()] = index
    return [joint_by_name[j.name] for j in JOINTS], [link_by_name[n] for n in LINK_NAMES]


def _stop_reason(
    p: Any,
    cid: int,
    item: dict[str, Any],
    chair: ChairBody,
    settings: SimulationSettings,
    step: int,
    min_steps: int,
) -> str | None:
    agent = item["agent"]
    position, _ = p.getBasePositionAndOrientation(agent, physicsClientId=cid)
    if position[2] - chair.z_min_m < settings.give_up_height_m:
        return "fell"
    # A sitter's pelvis, chest or head never touches the floor: the drop has failed.
    for contact in p.getContactPoints(bodyA=agent, bodyB=item["floor"], physicsClientId=cid):
        if contact[3] in item["trunk"]:
            return "fell"
    if step < min_steps:
        return None
    linear, angular = p.getBaseVelocity(agent, physicsClientId=cid)
    states = p.getJointStates(agent, item["joints"], physicsClientId=cid)
    joint_speed = max(abs(s[1]) for s in states)
    at_rest = (
        math.sqrt(sum(v * v for v in linear)) < settings.rest_linear_mps
        and math.sqrt(sum(w * w for w in angular)) < settings.rest_angular_rps
        and joint_speed < settings.rest_joint_rps
    )
    item["rest"] = item["rest"] + 1 if at_rest else 0
    return "rest" if item["rest"] >= settings.rest_checks else None


def _measure(
    p: Any, cid: int, item: dict[str, Any], chair: ChairBody, step: int, stopped_by: str
) -> RawDrop:
    agent, chair_body = item["agent"], item["chair"]
    # T_world_chair: the chair body's pose composed with the body -> OBB frame offset.
    chair_position, chair_quat = p.getBasePositionAndOrientation(chair_body, physicsClientId=cid)
    R_world_chair = np.array(p.getMatrixFromQuaternion(chair_quat)).reshape(3, 3)
    t_world_chair = np.array(chair_position) - R_world_chair @ chair.com_obb_m
    R_chair_world = R_world_chair.T

    def to_chair(point: np.ndarray) -> np.ndarray:
        return R_chair_world @ (np.asarray(point) - t_world_chair)

    base_position, base_quat = p.getBasePositionAndOrientation(agent, physicsClientId=cid)
    R_world_pelvis = np.array(p.getMatrixFromQuaternion(base_quat)).reshape(3, 3)
    R_chair_pelvis = R_chair_world @ R_world_pelvis
    position = to_chair(base_position)
    yaw = yaw_of(R_chair_pelvis)
    link_z = [R_chair_pelvis[:, 2]]
    link_poses = np.tile(np.eye(4), (len(item["links"]), 1, 1))
    link_poses[0, :3, :3], link_poses[0, :3, 3] = R_chair_pelvis, position
    for k, link_index in enumerate(item["links"][1:], start=1):
        state = p.getLinkState(agent, link_index, physicsClientId=cid)
        R_world_link = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        link_z.append(R_chair_world @ R_world_link[:, 2])
        link_poses[k, :3, :3], link_poses[k, :3, 3] = (
            R_chair_world @ R_world_link,
            to_chair(state[4]),
        )
    joints = p.getJointStates(agent, item["joints"], physicsClientId=cid)
    position_of_link = {index: k for k, index in enumerate(item["links"])}
    contacts = np.zeros(len(LINK_NAMES), dtype=int)
    for contact in p.getContactPoints(bodyA=agent, bodyB=chair_body, physicsClientId=cid):
        contacts[position_of_link[contact[3]]] += 1
    return RawDrop(
        spec=item["spec"],
        position=position,
        yaw=yaw,
        joint_angles=np.array([s[0] for s in joints]),
        link_z=np.array(link_z),
        contacts=contacts,
        sitting_height_m=float(base_position[2] - chair.z_min_m),
        steps=step,
        stopped_by=stopped_by,
        link_poses=link_poses,
    )
