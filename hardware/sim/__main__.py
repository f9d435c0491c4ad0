"""Figures of the simulated world: ``python -m bearchair.hardware.sim [--out DIR] [--seed N]``.

Prints build, physics and capture timings, depth accuracy against the true chair, and
from how far the arm camera (looking from the ready configuration) detects the tag on
the NAO's head; writes pictures of the scene to ``--out``.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import cast

import cv2
import numpy as np

from bearchair.core.arena import HUMANOID_TAG
from bearchair.core.geometry import transform_points
from bearchair.hardware.interfaces import RGBDFrame
from bearchair.hardware.sim.world import SimConfig, SimWorld


def _tag_seen(world: SimWorld) -> bool:
    dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, HUMANOID_TAG.dictionary))
    detector = cv2.aruco.ArucoDetector(dictionary, cv2.aruco.DetectorParameters())
    frame = world.panda.capture()
    _, ids, _ = detector.detectMarkers(frame.rgb)
    return ids is not None and HUMANOID_TAG.marker_id in ids.ravel()


def main() -> None:
    """Runs the measurements and prints them."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("sim-pictures"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--chair", type=Path, default=None)
    args = parser.parse_args()

    start = time.perf_counter()
    world = SimWorld(SimConfig(chair_path=args.chair, seed=args.seed))
    print(f"build: {time.perf_counter() - start:.2f} s")
    with world:
        _print_physics_speed(world)
        frame = _print_capture_and_depth_accuracy(world)
        args.out.mkdir(parents=True, exist_ok=True)
        world.render_png(args.out / "perspective.png")
        world.render_png(args.out / "top.png", "top")
        import PIL.Image

        PIL.Image.fromarray(frame.rgb).save(args.out / "camera.png")
        _print_tag_range(world)
    print(f"pictures in {args.out}")


def _print_physics_speed(world: SimWorld) -> None:
    """Simulated over wall seconds for 5 s standing still, then 5 s walking at 0.1 m/s."""
    start = time.perf_counter()
    world.clock.sleep(5.0)
    elapsed = time.perf_counter() - start
    print(f"physics, standing still: {5.0 / elapsed:.1f}x real time ({1200 / elapsed:.0f} steps/s)")
    world.nao.set_velocity(0.1, 0.0, 0.0)
    start = time.perf_counter()
    world.clock.sleep(5.0)
    elapsed = time.perf_counter() - start
    world.nao.stop()
    print(f"physics, walking: {5.0 / elapsed:.1f}x real time")


def _print_capture_and_depth_accuracy(world: SimWorld) -> RGBDFrame:
    """Times five noisy captures and measures the last one's chair pixels against the true
    chair surface; returns that frame."""
    start = time.perf_counter()
    frames = [world.panda.capture() for _ in range(5)]
    print(f"capture 640x480 with noise: {(time.perf_counter() - start) / 5 * 1000:.0f} ms")
    frame = frames[-1]
    view = world.panda.last_view
    assert view is not None  # capture() sets it
    mask = (view.segmentation == world.chair.body) & (frame.depth_m > 0)
    v, u = np.nonzero(mask)
    z = frame.depth_m[v, u].astype(float)
    K = frame.intrinsics
    points = transform_points(
        frame.T_world_camera,
        np.column_stack([(u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z]),
    )
    import open3d as o3d

    # open3d's stubs lose the defaults of Tensor's dtype and device (the array's, the CPU).
    tensor = cast(Callable[[np.ndarray], o3d.core.Tensor], o3d.core.Tensor)
    scene = o3d.t.geometry.RaycastingScene()
    mesh = world.chair_mesh_true
    scene.add_triangles(
        tensor(np.asarray(mesh.vertices, np.float32)), tensor(np.asarray(mesh.faces, np.uint32))
    )
    distance = scene.compute_distance(tensor(points.astype(np.float32))).numpy()
    print(
        f"chair depth pixels: {mask.sum()}, range {z.min():.2f}-{z.max():.2f} m, distance to "
        f"true surface median {np.median(distance) * 1000:.1f} mm, "
        f"90% {np.percentile(distance, 90) * 1000:.1f} mm"
    )
    return frame


def _print_tag_range(world: SimWorld) -> None:
    """From which NAO positions on the x axis (facing the arm) the camera sees its tag."""
    seen = []
    for x in np.arange(1.9, 0.5, -0.1):
        world.nao._true = np.array([x, 0.0, math.pi])
        world.nao._odometry = world.nao._true.copy()
        world.nao._place_body()
        if _tag_seen(world):
            seen.append(round(float(x), 2))
    print(f"tag detected from the ready configuration with the NAO at x = {seen}")


if __name__ == "__main__":
    main()
