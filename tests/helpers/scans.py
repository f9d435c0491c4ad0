"""Synthetic scans of a chair: the frames the wrist camera sees."""

from __future__ import annotations

from bearchair.testing.synthetic_scenes import SyntheticArm, SyntheticScene


def frames_of(mesh, T_world_chair, views, seed=3):
    """The frames the synthetic arm captures at each of ``views`` (joint configurations)
    of ``mesh`` placed at ``T_world_chair`` in a synthetic scene."""
    scene = SyntheticScene(seed=seed)
    scene.add_mesh(mesh, T_world_chair)
    arm = SyntheticArm(scene)
    try:
        frames = []
        for joints in views:
            arm.move_to(joints)
            frames.append(arm.capture())
        return frames
    finally:
        arm.close()
        scene.close()
