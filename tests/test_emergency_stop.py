"""Emergency stop in the simulated world: from the call to every actuator still, per stage.

Each mission stage commands its own motions (ScanChair and MakeChairAccessible move the
arm, WalkToChair walks and moves the arm to the overview, SeatBear plays a joint
trajectory and opens the hands, ReleaseAndStand opens the hands and stands up; Imagine
moves nothing). Each test starts that stage's motions in a worker, as the mission's
leaves do, calls ``Robot.emergency_stop()`` from the main thread while they run, and
counts the robot (simulated) time until every actuator is still: the Panda's joints
slower than :data:`STILL_RADPS`, the NAO's pose and joints unchanged over a step. The
bound is 0.2 s of robot time; the workers must end (with an error) and later motions
are refused.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from hardware.sim.world import SimConfig, SimWorld
from skills.perception.views import HOME_CONFIGURATION, SCAN_CONFIGURATIONS

STOP_BOUND_S = 0.2
STILL_RADPS = 0.01
"""Joint speed below which the arm counts as still (the encoders' noise is about this)."""


def _nao_state(world: SimWorld) -> np.ndarray:
    pose = world.nao.true_pose()
    joints = world.nao.joint_positions()
    return np.array([pose.x, pose.y, pose.theta, *joints.values()])


def _still_after(world: SimWorld, limit_s: float = 2.0) -> float:
    """Steps the world until every actuator is still; the robot time that took (seconds)."""
    clock = world.clock
    start = clock.now()
    previous = _nao_state(world)
    while clock.now() - start < limit_s:
        clock.step()
        state = _nao_state(world)
        arm_still = np.max(np.abs(world.panda.joint_velocities())) < STILL_RADPS
        if arm_still and np.allclose(state, previous, atol=1e-9, rtol=0.0):
            return clock.now() - start
        previous = state
    return float("inf")


def _walk(world: SimWorld, stop: threading.Event) -> None:
    # The walking controller commands a velocity and lets time pass, step after step.
    while not stop.is_set():
        world.nao.set_velocity(0.1, 0.0, 0.3)
        world.clock.sleep(0.05)


def _seat_trajectory(world: SimWorld) -> None:
    names = ["LHipPitch", "RHipPitch", "LKneePitch", "RKneePitch"]
    now = np.array([world.nao.joint_positions(names)[name] for name in names])
    target = now + np.array([-0.4, -0.4, 0.8, 0.8])
    world.nao.play_joint_trajectory(names, [2.0, 4.0], np.vstack([target, now]))


def _hands(world: SimWorld) -> None:
    for _ in range(40):
        world.nao.set_hands(True)
        world.nao.set_hands(False)


STAGE_MOTIONS = {
    "ScanChair": lambda world, stop: world.panda.move_to(SCAN_CONFIGURATIONS[2]),
    "ImagineSitting": lambda world, stop: world.clock.sleep(3.0),
    "MakeChairAccessible": lambda world, stop: world.panda.move_to(SCAN_CONFIGURATIONS[3]),
    "WalkToChair": _walk,
    "WalkToChair-overview": lambda world, stop: world.panda.move_to(SCAN_CONFIGURATIONS[0]),
    "SeatBear": lambda world, stop: _seat_trajectory(world),
    "ReleaseAndStand": lambda world, stop: _hands(world),
}


@pytest.mark.parametrize("stage", list(STAGE_MOTIONS))
def test_emergency_stop_stills_every_actuator_within_bound(stage):
    with SimWorld(SimConfig(seed=1, camera_noise=False)) as world:
        world.panda.move_to(HOME_CONFIGURATION)
        stop_walking = threading.Event()
        errors: list[BaseException] = []

        def worker() -> None:
            try:
                STAGE_MOTIONS[stage](world, stop_walking)
            except RuntimeError as error:
                errors.append(error)

        thread = threading.Thread(target=worker, daemon=True)
        thread.start()
        # Let the motion get going: the worker's sleeps advance simulated time.
        started = world.clock.now()
        while world.clock.now() - started < 0.6 and thread.is_alive():
            threading.Event().wait(0.005)
        world.robot.emergency_stop()
        stop_walking.set()
        thread.join(timeout=20.0)
        assert not thread.is_alive(), f"{stage}: the worker did not end after the stop"
        still_s = _still_after(world)
        assert still_s <= STOP_BOUND_S, f"{stage}: still only after {still_s:.3f} s"
        with pytest.raises(RuntimeError, match="emergency-stopped"):
            world.nao.set_velocity(0.1, 0.0, 0.0)
        with pytest.raises(RuntimeError, match="emergency-stopped"):
            world.panda.move_to(HOME_CONFIGURATION)
        if stage in ("ScanChair", "MakeChairAccessible", "WalkToChair-overview", "SeatBear"):
            assert errors and "emergency-stopped" in str(errors[0])


def test_emergency_stop_measures_the_arm_braking_time():
    """The arm at full scanning speed: the robot time from the stop to still, printed."""
    with SimWorld(SimConfig(seed=2, camera_noise=False)) as world:
        world.panda.move_to(HOME_CONFIGURATION)
        errors: list[BaseException] = []

        def move() -> None:
            try:
                world.panda.move_to(SCAN_CONFIGURATIONS[4])
            except RuntimeError as error:
                errors.append(error)

        thread = threading.Thread(target=move, daemon=True)
        thread.start()
        while np.max(np.abs(world.panda.joint_velocities())) < 1.0:
            threading.Event().wait(0.002)
        speed = float(np.max(np.abs(world.panda.joint_velocities())))
        world.robot.emergency_stop()
        thread.join(timeout=20.0)
        still_s = _still_after(world)
        print(f"arm at {speed:.2f} rad/s still after {still_s * 1000:.0f} ms of robot time")
        assert speed > 1.0 and still_s <= STOP_BOUND_S
        assert errors, "the interrupted move_to must raise"
