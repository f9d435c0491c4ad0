"""The Carmine noise model and the projection used by the simulated wrist camera."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from bearchair.hardware.sim.camera import CARMINE_INTRINSICS, CarmineNoise, opengl_matrices


def test_depth_noise_grows_with_the_square_of_distance_and_pixels_go_missing():
    rng = np.random.default_rng(0)
    rgb = np.full((480, 640, 3), 128, np.uint8)
    sigmas = {}
    for z in (0.5, 1.0, 2.0):
        depth = np.full((480, 640), z, np.float32)
        _, noisy = CarmineNoise().apply(rgb, depth, CARMINE_INTRINSICS, rng)
        valid = noisy > 0
        assert 0.96 < valid.mean() < 0.99  # about 2 % random dropouts
        sigmas[z] = float(np.std(noisy[valid] - z))
        assert abs(float(np.mean(noisy[valid])) - z) < 0.2 * sigmas[z] + 1e-4
    for z, sigma in sigmas.items():
        assert sigma == pytest.approx(1.5e-3 * z**2, rel=0.25)
    for z in (0.2, 4.0):
        depth = np.full((480, 640), z, np.float32)
        _, noisy = CarmineNoise().apply(rgb, depth, CARMINE_INTRINSICS, rng)
        assert not np.any(noisy), "outside 0.35-3.5 m nothing is measured"


def test_depth_edges_lose_pixels():
    rng = np.random.default_rng(1)
    depth = np.full((480, 640), 2.0, np.float32)
    depth[:, 320:] = 1.0
    _, noisy = CarmineNoise().apply(
        np.zeros((480, 640, 3), np.uint8), depth, CARMINE_INTRINSICS, rng
    )
    edge_missing = (noisy[:, 319:321] == 0).mean()
    assert 0.3 < edge_missing < 0.7


def test_projection_reproduces_the_pinhole_model():
    T_world_camera = np.eye(4)
    view, projection = opengl_matrices(T_world_camera, CARMINE_INTRINSICS)
    V = np.array(view).reshape(4, 4).T
    P = np.array(projection).reshape(4, 4).T
    K = CARMINE_INTRINSICS
    point = np.array([0.3, -0.2, 1.7, 1.0])  # OpenCV camera frame = world frame here
    clip = P @ V @ point
    ndc = clip[:3] / clip[3]
    u = (ndc[0] + 1.0) / 2.0 * K.width - 0.5
    v = (1.0 - ndc[1]) / 2.0 * K.height - 0.5
    assert u == pytest.approx(K.fx * 0.3 / 1.7 + K.cx, abs=1e-6)
    assert v == pytest.approx(K.fy * -0.2 / 1.7 + K.cy, abs=1e-6)


def test_world_is_usable_from_two_threads():
    from bearchair.hardware.sim.world import SimConfig, SimWorld

    with SimWorld(SimConfig(seed=2)) as world:
        frames = []

        def capture_while_walking() -> None:
            for _ in range(3):
                frames.append(world.panda.capture())

        worker = threading.Thread(target=capture_while_walking)
        world.nao.set_velocity(0.1, 0.0, 0.0)
        worker.start()
        world.clock.sleep(2.0)
        worker.join(timeout=60)
        assert not worker.is_alive() and len(frames) == 3
        assert all(frame.depth_m.shape == (480, 640) for frame in frames)


def test_helper_understands_only_rotation_instructions():
    from bearchair.hardware.sim.helper import parse_instruction

    heard = parse_instruction(
        "Please rotate the chair about the vertical axis clockwise for 60 degrees"
    )
    assert heard is not None and heard.clockwise and heard.angle_deg == 60.0
    assert heard.signed_angle_rad < 0.0
    heard = parse_instruction(
        "Please rotate the chair about the vertical axis counterclockwise for 150 degrees."
    )
    assert heard is not None and not heard.clockwise and heard.angle_deg == 150.0
    assert parse_instruction("Hello, I am going to sit the bear on the chair") is None
