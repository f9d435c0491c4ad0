"""The chair as a dynamic body: visual from the mesh, collision from its convex pieces.

The chair frame is the mesh's own frame shifted so that the centre of its x-y bounding
box is the origin and its lowest point (of the mesh or of any convex piece) is z = 0.
The helper turns the chair about this frame's z axis.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np
import pybullet
import trimesh

from hardware.sim.bullet import (
    LockedBullet,
    T_world_base_link,
    reset_base_link,
    rotation_to_quaternion,
    sim_cache_dir,
)
from skills.meshes import convex_pieces, mesh_digest

log = logging.getLogger(__name__)

CHAIR_MASS_KG = 2.0
"""A child's chair. The calibration meshes are mostly open triangle soups whose volume
is undefined, so the mass is fixed and only its distribution comes from the mesh."""

CHAIR_FRICTION = 0.8


def centred_chair_mesh(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, list[trimesh.Trimesh]]:
    """The mesh and its convex pieces in the chair frame (x-y centred, lowest point z = 0)."""
    pieces = convex_pieces(mesh)
    if not pieces:
        raise ValueError("convex decomposition of the chair produced no pieces")
    bounds = mesh.bounds
    lowest = min(float(bounds[0, 2]), min(float(piece.bounds[0, 2]) for piece in pieces))
    offset = -np.array(
        [(bounds[0, 0] + bounds[1, 0]) / 2.0, (bounds[0, 1] + bounds[1, 1]) / 2.0, lowest]
    )
    centred = mesh.copy()
    centred.apply_translation(offset)
    moved = []
    for piece in pieces:
        piece = piece.copy()
        piece.apply_translation(offset)
        moved.append(piece)
    return centred, moved


def mass_properties(pieces: list[trimesh.Trimesh], mass_kg: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre of mass and 3x3 inertia tensor (about the COM) of the pieces at uniform density.

    Overlaps between pieces are counted twice; V-HACD pieces barely overlap.
    """
    volumes = np.array([abs(piece.volume) for piece in pieces])
    density = mass_kg / volumes.sum()
    masses = volumes * density
    centres = np.array([piece.center_mass for piece in pieces])
    com = (masses[:, None] * centres).sum(axis=0) / masses.sum()
    inertia = np.zeros((3, 3))
    for piece, mass, centre in zip(pieces, masses, centres, strict=True):
        piece_inertia = np.asarray(piece.moment_inertia) * (mass / abs(piece.mass))
        d = centre - com
        inertia += piece_inertia + mass * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return com, inertia


def _write_assets(mesh: trimesh.Trimesh, pieces: list[trimesh.Trimesh]) -> tuple[Path, Path]:
    folder = sim_cache_dir() / "chairs"
    folder.mkdir(parents=True, exist_ok=True)
    digest = mesh_digest(mesh)
    visual = folder / f"{digest}-visual.obj"
    collision = folder / f"{digest}-collision.obj"
    if not visual.exists():
        scratch = visual.with_suffix(f".{os.getpid()}.tmp.obj")
        mesh.export(scratch, include_normals=False, include_texture=False)
        os.replace(scratch, visual)
    if not collision.exists():
        lines = []
        offset = 1
        for index, piece in enumerate(pieces):
            lines.append(f"o piece{index}")
            lines.extend(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in piece.vertices)
            lines.extend(f"f {a + offset} {b + offset} {c + offset}" for a, b, c in piece.faces)
            offset += len(piece.vertices)
        scratch = collision.with_suffix(f".{os.getpid()}.tmp.obj")
        scratch.write_text("\n".join(lines) + "\n")
        os.replace(scratch, collision)
    return visual, collision


class SimChair:
    """A chair body in the world.

    Attributes:
        body: pybullet body id.
        mesh_local: the chair mesh in the chair frame.
        pieces_local: its convex collision pieces in the chair frame.
    """

    def __init__(
        self, bullet: LockedBullet, mesh: trimesh.Trimesh, T_world_chair: np.ndarray
    ) -> None:
        self._bullet = bullet
        self.mesh_local, self.pieces_local = centred_chair_mesh(mesh)
        visual_path, collision_path = _write_assets(self.mesh_local, self.pieces_local)
        com, inertia = mass_properties(self.pieces_local, CHAIR_MASS_KG)
        principal, axes = np.linalg.eigh(inertia)
        if np.linalg.det(axes) < 0.0:
            axes[:, 0] = -axes[:, 0]
        with bullet.lock:
            collision = bullet.createCollisionShape(
                pybullet.GEOM_MESH, fileName=str(collision_path)
            )
            visual = bullet.createVisualShape(
                pybullet.GEOM_MESH, fileName=str(visual_path), rgbaColor=[0.75, 0.55, 0.35, 1.0]
            )
            self.body = bullet.createMultiBody(
                baseMass=CHAIR_MASS_KG,
                baseCollisionShapeIndex=collision,
                baseVisualShapeIndex=visual,
                baseInertialFramePosition=list(map(float, com)),
                baseInertialFrameOrientation=rotation_to_quaternion(axes),
            )
            bullet.changeDynamics(
                self.body,
                -1,
                localInertiaDiagonal=list(map(float, np.maximum(principal, 1e-6))),
                lateralFriction=CHAIR_FRICTION,
            )
            self.set_T_world_chair(T_world_chair)

    def T_world_chair(self) -> np.ndarray:
        """The chair frame in the world (ground truth)."""
        return T_world_base_link(self._bullet, self.body)

    def set_T_world_chair(self, T_world_chair: np.ndarray) -> None:
        """Teleports the chair (at rest)."""
        reset_base_link(self._bullet, self.body, T_world_chair)

    def mesh_world(self) -> trimesh.Trimesh:
        """The chair mesh at its current pose."""
        return self.mesh_local.copy().apply_transform(self.T_world_chair())
