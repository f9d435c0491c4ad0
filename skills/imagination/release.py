"""Release imagination: will the bear stay seated when the hands open?

The paper imagines the sitting by dropping a virtual child onto the scanned chair; this
imagines the release the same way. The bear model is the simulated world's own bear
(:func:`bearchair.hardware.bear_model.create_bear_body`: shape, mass, friction), put where
the planned goal posture holds it and let go onto the *reconstructed* chair (a static
body colliding as the scan's triangle mesh, as the world's chair collides as its mesh),
once as planned and once for each perturbation the real release will see: the walk
stops anywhere within its stop box (:class:`bearchair.skills.control.walk.WalkGains`),
and the scanned seat's height is a few millimetres off. Each settled bear is judged by
the judge's own criteria (:func:`bearchair.hardware.seating_criteria.judge_bear_pose`) against
the imagined sitting direction. Nothing here sees the simulated world's true chair.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time
from typing import Any, NamedTuple

import numpy as np
import pybullet
import trimesh
from pybullet_utils import bullet_client

from bearchair.core.bullet_poses import matrix_to_pose, pose_to_matrix
from bearchair.core.geometry import make_transform, rot_z, yaw_of
from bearchair.core.meshes import cache_dir, mesh_digest
from bearchair.core.nao_carrying import BEAR_TORSO_DEPTH_M
from bearchair.core.runtime import RUNTIME
from bearchair.core.se2 import SE2Pose
from bearchair.core.streams import silenced_fds
from bearchair.hardware.bear_model import BEAR_PARTS, T_bear_base, create_bear_body
from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.hardware.seating_criteria import judge_bear_pose

PHYSICS_RATE_HZ = 240.0
"""The release's physics steps per second: pybullet's default step (1/240 s), the one the
simulated world steps at too."""
CHAIR_FRICTION = 0.8
"""Friction of a chair's surface (wood, plastic or fabric against plush): the simulated
world's chairs have the same."""
FLOOR_FRICTION = 0.9
"""A lab floor's friction, as the simulated world's."""
SETTLE_MAX_S = 1.5
"""Longest a released bear is simulated; one that has not come to rest by then is judged
where it is (in the campaign's scans a bear that tipped had fallen within 1 s)."""
SETTLE_MIN_S = 0.4
REST_SPEED_M_S = 0.03
REST_SPIN_RAD_S = 0.3
REST_HOLD_S = 0.1
"""After ``SETTLE_MIN_S``, a bear moving slower than these for this long is at rest: on a
scan's bumpy surface it rocks by millimetres for a second more (0.01 m/s, 0.1 rad/s),
which no longer changes what the judge says."""
SEAT_PATCH_MARGIN_M = 0.02
"""How far the seat map's patch reaches beyond the bear's torso footprint (metres)."""
SEAT_PATCH_SEARCH_M = 0.03
"""A scanned surface within this of the seat map's top under the footprint counts as the
seat (metres)."""
SEAT_EDGE_PROBES_M = (0.01, 0.02, 0.03)
"""Where the scan is looked at beyond a footprint corner it has no seat under (metres,
outward along the footprint's diagonal): one TSDF voxel (0.008 m) at a time, as far as
the patch reaches past the footprint (``SEAT_PATCH_MARGIN_M``) and a voxel more. Seat seen
there: the corner is over a hole; none: over the seat's edge."""
SCAN_HEIGHT_ERROR_M = 0.004
"""How far the scanned seat's top may lie off the true one (2-5 mm above it in the
campaign trials): a release this much higher is imagined too."""

BEAR_TORSO_WIDTH_M = BEAR_PARTS[0].size[1]
"""The bear torso's width (metres): the box it sits on, the bear's first part."""

_local = threading.local()


class ImaginedRelease(NamedTuple):
    """One imagined release: what was perturbed and the judge's verdict on the settled bear."""

    perturbation: str
    judgement: SeatingJudgement


class ReleasePrediction(NamedTuple):
    """What the release imagination predicts for a planned release.

    Attributes:
        stays: the bear stays seated in at least half of the perturbed releases
            (:func:`perturbations`).
        releases: the imagined releases, the planned one first, until the majority was
            decided.
        T_world_bear_release: where the plan lets the bear go (world frame).
        seconds: wall time of the imagination.
        seat_patched: the scan had a hole in the seat under the bear's footprint, and the
            seat map's seat was added there (see :func:`imagine_release`).
        cpu_seconds: this thread's CPU time in it (the wall time on a loaded machine is
            longer).
    """

    stays: bool
    releases: tuple[ImaginedRelease, ...]
    T_world_bear_release: np.ndarray
    seconds: float
    seat_patched: bool = False
    cpu_seconds: float = 0.0

    @property
    def staying(self) -> int:
        return sum(r.judgement.seated for r in self.releases)

    @property
    def tipped_on_seat(self) -> bool:
        """The bear is predicted to fall, and every imagined bear that fell came to rest on
        the scanned chair (tilted or turned too far) rather than through it onto the
        floor: a fall the scan's seat itself causes, not one through a hole in the scan."""
        fallen = [r.judgement for r in self.releases if not r.judgement.seated]
        return not self.stays and bool(fallen) and all(j.on_seat for j in fallen)

    @property
    def reason(self) -> str:
        """Why the bear falls in the imagined releases where it does (most frequent first)."""
        reasons = [r.judgement.reason for r in self.releases if not r.judgement.seated]
        return max(set(reasons), key=reasons.count) if reasons else ""

    def to_json(self) -> dict[str, Any]:
        """For ``summary.json``: the prediction and the planned release's settle pose."""
        settled = self.releases[0].judgement
        T = np.asarray(settled.T_world_bear)
        return {
            "stays": self.stays,
            "staying": f"{self.staying}/{len(self.releases)}",
            "reason": self.reason,
            "released_at_m": [round(float(v), 4) for v in self.T_world_bear_release[:3, 3]],
            "settled_at_m": [round(float(v), 4) for v in T[:3, 3]],
            "settled_yaw_deg": round(math.degrees(yaw_of(T)), 1),
            "settled_tilt_deg": round(float(settled.torso_tilt_deg), 1),
            "seconds": round(self.seconds, 3),
            "cpu_seconds": round(self.cpu_seconds, 3),
            "seat_patched": self.seat_patched,
        }


def perturbations(stop_m: float, stop_rad: float) -> list[tuple[str, np.ndarray]]:
    """(label, T_release_perturbed) of the planned release and its perturbations: the NAO
    stopped at each side of its stop box (``stop_m`` along and across, ``stop_rad`` turned),
    and the seat scanned ``SCAN_HEIGHT_ERROR_M`` too high (the bear let go that much higher
    over the true seat)."""
    out = [("as planned", np.eye(4))]
    for sign in (1.0, -1.0):
        out.append((f"walk {sign * stop_m * 1000:+.0f} mm along", _offset(sign * stop_m, 0, 0)))
        turned = make_transform(rot_z(sign * stop_rad), np.array([0.0, sign * stop_m, 0.0]))
        out.append((f"walk {sign * stop_m * 1000:+.0f} mm across, turned", turned))
    out.append(
        (f"seat {SCAN_HEIGHT_ERROR_M * 1000:.0f} mm lower", _offset(0, 0, SCAN_HEIGHT_ERROR_M))
    )
    return out


def _offset(x: float, y: float, z: float) -> np.ndarray:
    transform = np.eye(4)
    transform[:3, 3] = (x, y, z)
    return transform


def bear_release_pose(
    humanoid_pose: SE2Pose, bear_base_xz: np.ndarray, bear_up_xz: np.ndarray
) -> np.ndarray:
    """The bear frame in the world where a posture lets it go.

    Args:
        humanoid_pose: the NAO's planar pose.
        bear_base_xz: the bear's seat point (x forward, z up) in the NAO frame.
        bear_up_xz: the bear's torso axis (x, z) in the NAO frame; x > 0 leans its top away
            from the NAO, toward the chair's back.
    """
    up = np.array([bear_up_xz[0], 0.0, bear_up_xz[1]])
    up /= np.linalg.norm(up)
    forward = np.array([-up[2], 0.0, up[0]])  # the bear faces the NAO
    T_nao_bear = np.eye(4)
    T_nao_bear[:3, 0], T_nao_bear[:3, 1], T_nao_bear[:3, 2] = forward, np.cross(up, forward), up
    T_nao_bear[:3, 3] = (bear_base_xz[0], 0.0, bear_base_xz[1])
    return humanoid_pose.as_transform() @ T_nao_bear


def imagine_release(
    chair_mesh: trimesh.Trimesh,
    T_world_bear_release: np.ndarray,
    sitting_yaw_rad: float,
    humanoid_pose: SE2Pose,
    *,
    stop_m: float = 0.005,
    stop_rad: float = math.radians(2.5),
    seat_top_z: float | None = None,
) -> ReleasePrediction:
    """Imagines letting the bear go at ``T_world_bear_release`` over the scanned chair.

    A scan can lose part of a seat under the sitting point (a seat the views saw only in
    part, a thin or slatted one the TSDF thins out) where the planner's seat map, taken from the
    scan in a band around p, still has it: the bear would fall through the hole in the
    imagination but not on the chair. Given ``seat_top_z``, where the scan has a hole near
    that height under the bear's torso footprint (not where the footprint reaches past the
    seat's edge: :meth:`_ReleaseWorld.patch_seat`), the seat map's seat is added there as a
    thin slab (the footprint and ``SEAT_PATCH_MARGIN_M`` around it).

    Args:
        chair_mesh: the reconstructed chair, world frame (floor at z = 0).
        T_world_bear_release: the bear frame where the hands open.
        sitting_yaw_rad: the imagined sitting direction the bear must face.
        humanoid_pose: where the NAO stands (the walk's stop error is about its frame).
        stop_m, stop_rad: the walk's stop box (half sides).
        seat_top_z: the seat map's seat top under the bear (metres), if known.
    """
    started, started_cpu = time.perf_counter(), time.thread_time()
    world = _world(chair_mesh)
    T_world_nao = humanoid_pose.as_transform()
    T_nao_bear = np.linalg.inv(T_world_nao) @ T_world_bear_release
    patched = seat_top_z is not None and world.patch_seat(T_world_bear_release, seat_top_z)
    candidates = perturbations(stop_m, stop_rad)
    releases: list[ImaginedRelease] = []
    for label, T_perturbed in candidates:
        T_start = T_world_nao @ T_perturbed @ T_nao_bear
        releases.append(ImaginedRelease(label, world.release(T_start, sitting_yaw_rad)))
        staying = sum(r.judgement.seated for r in releases)
        if 2 * staying >= len(candidates) or 2 * (len(releases) - staying) > len(candidates):
            break  # the majority is decided: the rest cannot change the prediction
    world.remove_patch()
    stays = 2 * sum(r.judgement.seated for r in releases) >= len(candidates)
    return ReleasePrediction(
        stays,
        tuple(releases),
        T_world_bear_release,
        time.perf_counter() - started,
        patched,
        time.thread_time() - started_cpu,
    )


class _ReleaseWorld:
    """A DIRECT pybullet world with the floor, one scanned chair and the bear model."""

    def __init__(self, chair_mesh: trimesh.Trimesh) -> None:
        self.digest = mesh_digest(chair_mesh)
        with silenced_fds(1):  # pybullet prints its arguments on connecting
            self.client = bullet_client.BulletClient(connection_mode=pybullet.DIRECT)
        client = self.client
        client.setGravity(0.0, 0.0, -9.81)
        client.setTimeStep(1.0 / PHYSICS_RATE_HZ)
        plane = client.createCollisionShape(pybullet.GEOM_PLANE)
        self.floor = client.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=plane)
        client.changeDynamics(self.floor, -1, lateralFriction=FLOOR_FRICTION)
        shape = client.createCollisionShape(
            pybullet.GEOM_MESH,
            fileName=str(_mesh_file(chair_mesh, self.digest)),
            flags=pybullet.GEOM_FORCE_CONCAVE_TRIMESH,
        )
        self.chair = client.createMultiBody(baseMass=0.0, baseCollisionShapeIndex=shape)
        client.changeDynamics(self.chair, -1, lateralFriction=CHAIR_FRICTION)
        self.bear = create_bear_body(client)
        self.T_bear_base = T_bear_base()
        self.patch: int | None = None
        self.closed = False

    def patch_seat(self, T_world_bear: np.ndarray, seat_top_z: float) -> bool:
        """Adds the seat map's seat under the bear's footprint where the scan has a hole in
        the seat there; returns whether it did.

        The scan is looked at near ``seat_top_z`` under the footprint's middle and corners.
        A missing corner is a hole when the seat is seen beyond it (``SEAT_EDGE_PROBES_M``
        outward along the footprint's diagonal), the middle when a corner is seen: a thin
        seat the TSDF thinned out goes on around its holes, while a footprint reaching past
        the seat's edge hangs over nothing, and a patch there would hold up a bear that
        tips over the edge."""
        half = np.array([BEAR_TORSO_DEPTH_M / 2.0, BEAR_TORSO_WIDTH_M / 2.0])
        corners = [half * (sx, sy) for sx in (-1, 1) for sy in (-1, 1)]
        middle_seen, *corners_seen = self._seat_seen(
            T_world_bear, [np.zeros(2), *corners], seat_top_z
        )
        if middle_seen and all(corners_seen):
            return False
        holes = (not middle_seen and any(corners_seen)) or any(
            any(self._seat_seen(T_world_bear, _beyond(corner), seat_top_z))
            for corner, seen in zip(corners, corners_seen, strict=True)
            if not seen
        )
        if not holes:
            return False
        extents = half + SEAT_PATCH_MARGIN_M
        shape = self.client.createCollisionShape(
            pybullet.GEOM_BOX, halfExtents=[extents[0], extents[1], 0.005]
        )
        centre = [*T_world_bear[:2, 3], seat_top_z - 0.005]
        orientation = pybullet.getQuaternionFromEuler([0.0, 0.0, yaw_of(T_world_bear)])
        self.patch = self.client.createMultiBody(
            baseMass=0.0,
            baseCollisionShapeIndex=shape,
            basePosition=centre,
            baseOrientation=orientation,
        )
        self.client.changeDynamics(self.patch, -1, lateralFriction=CHAIR_FRICTION)
        return True

    def _seat_seen(
        self, T_world_bear: np.ndarray, points_bear: list[np.ndarray], seat_top_z: float
    ) -> list[bool]:
        """Whether the scan has a surface within ``SEAT_PATCH_SEARCH_M`` of ``seat_top_z``
        under each (x, y) point of the bear frame (metres)."""
        rays_from, rays_to = [], []
        for point in points_bear:
            x, y = (T_world_bear @ np.array([point[0], point[1], 0.0, 1.0]))[:2]
            rays_from.append([x, y, seat_top_z + SEAT_PATCH_SEARCH_M])
            rays_to.append([x, y, seat_top_z - SEAT_PATCH_SEARCH_M])
        return [hit[0] == self.chair for hit in self.client.rayTestBatch(rays_from, rays_to)]

    def remove_patch(self) -> None:
        if self.patch is not None:
            self.client.removeBody(self.patch)
            self.patch = None

    def release(self, T_world_bear: np.ndarray, sitting_yaw_rad: float) -> SeatingJudgement:
        """Lets the bear go at rest from ``T_world_bear``; the judge's verdict once it rests."""
        client = self.client
        position, orientation = matrix_to_pose(T_world_bear @ self.T_bear_base)
        client.resetBasePositionAndOrientation(self.bear, position, orientation)
        client.resetBaseVelocity(self.bear, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
        hold_steps = round(REST_HOLD_S * PHYSICS_RATE_HZ)
        min_steps = round(SETTLE_MIN_S * PHYSICS_RATE_HZ)
        still = 0
        for step in range(round(SETTLE_MAX_S * PHYSICS_RATE_HZ)):
            client.stepSimulation()
            linear, angular = client.getBaseVelocity(self.bear)
            slow = math.hypot(*linear) < REST_SPEED_M_S and math.hypot(*angular) < REST_SPIN_RAD_S
            still = still + 1 if slow else 0
            if still >= hold_steps and step >= min_steps:
                break
        position, orientation = client.getBasePositionAndOrientation(self.bear)
        T_settled = pose_to_matrix(position, orientation) @ np.linalg.inv(self.T_bear_base)
        contacts = client.getContactPoints(self.bear, self.chair)
        if self.patch is not None:
            contacts += client.getContactPoints(self.bear, self.patch)
        on_floor = bool(client.getContactPoints(self.bear, self.floor))
        return judge_bear_pose(
            T_settled, [np.asarray(c[5]) for c in contacts], on_floor, sitting_yaw_rad
        )

    def close(self) -> None:
        self.closed = True
        with contextlib.suppress(pybullet.error):
            self.client.disconnect()


def _beyond(corner: np.ndarray) -> list[np.ndarray]:
    """The points ``SEAT_EDGE_PROBES_M`` past a footprint corner (bear frame, metres),
    outward along the footprint's diagonal."""
    outward = corner / np.linalg.norm(corner)
    return [corner + step * outward for step in SEAT_EDGE_PROBES_M]


def _world(chair_mesh: trimesh.Trimesh) -> _ReleaseWorld:
    """This thread's release world for ``chair_mesh`` (rebuilt when the chair changes)."""
    world: _ReleaseWorld | None = getattr(_local, "world", None)
    if world is not None and not world.closed and world.digest == mesh_digest(chair_mesh):
        return world
    if world is not None:
        world.close()
    _local.world = _ReleaseWorld(chair_mesh)
    with _worlds_lock:
        _worlds[:] = [w for w in _worlds if not w.closed] + [_local.world]
    return _local.world


_worlds: list[_ReleaseWorld] = []
"""Every thread's open release world, so the runtime can close them all."""
_worlds_lock = threading.Lock()


def close_release_worlds() -> None:
    """Disconnects every release world's pybullet client (the runtime's reset and
    shutdown): an open one is process state that other pybullet users then share."""
    with _worlds_lock:
        worlds, _worlds[:] = list(_worlds), []
    for world in worlds:
        world.close()


def _shutdown_release_worlds(_bound_s: float) -> bool:
    close_release_worlds()  # a disconnect does not wait
    return True


RUNTIME.register("release worlds", reset=close_release_worlds, shutdown=_shutdown_release_worlds)


def _mesh_file(mesh: trimesh.Trimesh, digest: str) -> os.PathLike:
    """The mesh as an OBJ in the cache (pybullet loads meshes from files)."""
    folder = cache_dir() / "release"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{digest}.obj"
    if not path.exists():
        scratch = path.with_suffix(f".{os.getpid()}.tmp.obj")
        mesh.export(scratch, include_normals=False, include_texture=False)
        os.replace(scratch, path)
    return path
