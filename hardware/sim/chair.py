"""The chair as a static body whose collision shape is its own mesh.

The chair frame is the mesh's own frame shifted so that the centre of its x-y bounding
box is the origin and its lowest point is z = 0. The helper turns the chair about this
frame's z axis (kinematically: :mod:`bearchair.hardware.sim.helper` sets its pose every step).

Why static: pybullet collides with a concave triangle mesh exactly only when the body is
static. A dynamic chair needs convex pieces, and V-HACD's pieces of open, thin chair
meshes grew the chair by centimetres where the NAO works to a centimetre: the hull of a
seat between higher rails stood 2-4 cm above the seat (the bear was released on it and
tipped off), and hulls around seat fronts caught the carried bear that the planner,
working from the scan of the true surface, kept clear. What a static
chair cannot do is slide when pushed: nothing dynamic that touches it (the 0.2 kg bear)
could push a 2 kg chair far, and the NAO is kinematic in this world, so contacts between
the NAO and the chair are recorded (:mod:`bearchair.hardware.sim.contacts`) instead of moving it.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pybullet
import trimesh

from bearchair.core.meshes import mesh_digest
from bearchair.hardware.sim.bullet import (
    LockedBullet,
    T_world_base_link,
    reset_base_link,
    sim_cache_dir,
)

CHAIR_FRICTION = 0.8


def centred_chair_mesh(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """The mesh in the chair frame (x-y bounding box centred, lowest point z = 0)."""
    bounds = mesh.bounds
    offset = -np.array(
        [(bounds[0, 0] + bounds[1, 0]) / 2.0, (bounds[0, 1] + bounds[1, 1]) / 2.0, bounds[0, 2]]
    )
    return mesh.copy().apply_translation(offset)


def _write_mesh(mesh: trimesh.Trimesh) -> Path:
    folder = sim_cache_dir() / "chairs"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{mesh_digest(mesh)}.obj"
    if not path.exists():
        scratch = path.with_suffix(f".{os.getpid()}.tmp.obj")
        mesh.export(scratch, include_normals=False, include_texture=False)
        os.replace(scratch, path)
    return path


class SimChair:
    """A chair body in the world.

    Attributes:
        body: pybullet body id.
        mesh_local: the chair mesh in the chair frame.
    """

    def __init__(
        self, bullet: LockedBullet, mesh: trimesh.Trimesh, T_world_chair: np.ndarray
    ) -> None:
        self._bullet = bullet
        self.mesh_local = centred_chair_mesh(mesh)
        mesh_path = str(_write_mesh(self.mesh_local))
        with bullet.lock:
            collision = bullet.createCollisionShape(
                pybullet.GEOM_MESH, fileName=mesh_path, flags=pybullet.GEOM_FORCE_CONCAVE_TRIMESH
            )
            visual = bullet.createVisualShape(
                pybullet.GEOM_MESH, fileName=mesh_path, rgbaColor=[0.75, 0.55, 0.35, 1.0]
            )
            self.body = bullet.createMultiBody(
                baseMass=0.0, baseCollisionShapeIndex=collision, baseVisualShapeIndex=visual
            )
            bullet.changeDynamics(self.body, -1, lateralFriction=CHAIR_FRICTION)
            self.set_T_world_chair(T_world_chair)

    def T_world_chair(self) -> np.ndarray:
        """The chair frame in the world (ground truth)."""
        return T_world_base_link(self._bullet, self.body)

    def set_T_world_chair(self, T_world_chair: np.ndarray) -> None:
        """Moves the chair (the helper turns it by calling this every step)."""
        reset_base_link(self._bullet, self.body, T_world_chair)

    def mesh_world(self) -> trimesh.Trimesh:
        """The chair mesh at its current pose."""
        return self.mesh_local.copy().apply_transform(self.T_world_chair())
