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

Over the SDK stand-ins a third time with a slow link: every NAOqi call answered
:data:`SLOW_CALL_S` late (a bad Wi-Fi link) and NAOqi's blocking ``moveTo``. A ticker
keeps the paced world stepping while the stop goes out, and wall time is measured: the
arm's ``Robot::stop`` must arrive within :data:`ARM_SIGNAL_BOUND_S` of the signal and
every actuator be still within :data:`SLOW_STOP_BOUND_S`.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

from bearchair.hardware.interfaces import Robot
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.skills.perception.views import HOME_CONFIGURATION, SCAN_CONFIGURATIONS

STOP_BOUND_S = 0.2
SLOW_CALL_S = 0.3
ARM_SIGNAL_BOUND_S = 0.05
SLOW_STOP_BOUND_S = 0.5
STILL_RADPS = 0.01
"""Joint speed below which the arm counts as still (the encoders' noise is about this)."""


def _nao_state(world: SimWorld) -> np.ndarray:
    pose = world.nao.true_pose()
    joints = world.nao.joint_positions()
    return np.array([pose.x, pose.y, pose.theta, *joints.values()])


class MotionProbe:
    """A clock process: the last robot time at which any actuator moved.

    Still means the Panda's joints slower than :data:`STILL_RADPS` and the NAO's pose and
    joints unchanged since the previous physics step.
    """

    def __init__(self, world: SimWorld) -> None:
        self._world = world
        self._previous = _nao_state(world)
        self.last_moving_s = world.clock.now()
        self.last_moving_wall_s = time.monotonic()
        world.clock.add_process(self)

    def __call__(self, now_s: float, dt_s: float) -> None:
        state = _nao_state(self._world)
        arm_moving = np.max(np.abs(self._world.panda.joint_velocities())) >= STILL_RADPS
        if arm_moving or not np.allclose(state, self._previous, atol=1e-9, rtol=0.0):
            self.last_moving_s = now_s
            self.last_moving_wall_s = time.monotonic()
        self._previous = state


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


def _walk(world: SimWorld, robot: Robot, stop: threading.Event) -> None:
    # The walking controller commands a velocity and lets time pass, step after step.
    while not stop.is_set():
        robot.humanoid.set_velocity(0.1, 0.0, 0.3)
        robot.clock.sleep(0.05)


def _seat_trajectory(world: SimWorld, robot: Robot) -> None:
    names = ["LHipPitch", "RHipPitch", "LKneePitch", "RKneePitch"]
    now = np.array([world.nao.joint_positions(names)[name] for name in names])
    target = now + np.array([-0.4, -0.4, 0.8, 0.8])
    robot.humanoid.play_joint_trajectory(names, [2.0, 4.0], np.vstack([target, now]))


def _hands(robot: Robot) -> None:
    for _ in range(40):
        robot.humanoid.set_hands(True)
        robot.humanoid.set_hands(False)


def _scan_views(robot: Robot) -> None:
    # Every view in turn, as ScanChair does: seconds of robot time, so the stop always
    # lands mid-motion however fast the simulated world steps.
    for configuration in SCAN_CONFIGURATIONS:
        robot.arm.move_to(configuration)


def _overview_and_back(robot: Robot) -> None:
    # To the overview pose and back, repeatedly: the stop lands mid-motion however fast
    # the simulated world steps.
    for _ in range(5):
        robot.arm.move_to(SCAN_CONFIGURATIONS[0])
        robot.arm.move_to(HOME_CONFIGURATION)


STAGE_MOTIONS = {
    "ScanChair": lambda world, robot, stop: _scan_views(robot),
    "ImagineSitting": lambda world, robot, stop: robot.clock.sleep(3.0),
    "MakeChairAccessible": lambda world, robot, stop: _scan_views(robot),
    "WalkToChair": _walk,
    "WalkToChair-overview": lambda world, robot, stop: _overview_and_back(robot),
    "SeatBear": lambda world, robot, stop: _seat_trajectory(world, robot),
    "ReleaseAndStand": lambda world, robot, stop: _hands(robot),
}
INTERRUPTED_WITH_ERROR = ("ScanChair", "MakeChairAccessible", "WalkToChair-overview", "SeatBear")


@contextlib.contextmanager
def _robot(world: SimWorld, backend: str) -> Iterator[Robot]:
    """The simulated devices, or the real backends over the SDK stand-ins over them."""
    if backend == "sim":
        yield world.robot
        return
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin
    from bearchair.hardware.real.standins.simulated_bodies import (
        SimulatedNaoBody,
        robot_over_standins,
    )

    with NaoqiStandin(body=SimulatedNaoBody(world)) as standin:
        robot, session = robot_over_standins(world, standin)
        robot.humanoid.activate()
        if backend == "real-over-slow-standins":
            standin.call_latency_s = SLOW_CALL_S  # from here on: set up on a good link
        yield robot
        session.close()


@contextlib.contextmanager
def _ticking(world: SimWorld) -> Iterator[None]:
    """Keeps the paced world stepping (robot time about wall time) while inside."""
    done = threading.Event()

    def tick() -> None:
        while not done.is_set():
            world.clock.sleep(0.01)

    ticker = threading.Thread(target=tick, daemon=True)
    ticker.start()
    try:
        yield
    finally:
        done.set()
        ticker.join(5.0)


@pytest.mark.slow
@pytest.mark.parametrize("backend", ["sim", "real-over-standins", "real-over-slow-standins"])
@pytest.mark.parametrize("stage", list(STAGE_MOTIONS))
def test_emergency_stop_stills_every_actuator_within_bound(stage, backend):
    with SimWorld(SimConfig(seed=1, camera_noise=False)) as world, _robot(world, backend) as robot:
        robot.arm.move_to(HOME_CONFIGURATION)
        # Robot time as on the real robots: the stop comes from this thread in wall time.
        world.clock.pace_to_wall_clock()
        stop_walking = threading.Event()
        errors: list[BaseException] = []

        def worker() -> None:
            try:
                STAGE_MOTIONS[stage](world, robot, stop_walking)
            except RuntimeError as error:
                errors.append(error)

        probe = MotionProbe(world)
        thread = threading.Thread(target=worker, daemon=True)
        thread.start()
        # Let the motion get going: the worker's sleeps advance simulated time.
        started = world.clock.now()
        while world.clock.now() - started < 0.6 and thread.is_alive():
            threading.Event().wait(0.005)
        stopped_s = world.clock.now()
        slow = backend == "real-over-slow-standins"
        with _ticking(world) if slow else contextlib.nullcontext():
            signal_s = time.monotonic()
            robot.emergency_stop()
            stop_walking.set()
            thread.join(timeout=20.0)
            assert not thread.is_alive(), f"{stage}: the worker did not end after the stop"
            if slow:
                time.sleep(SLOW_STOP_BOUND_S + 0.3)  # long enough to see anything still moving
        if not slow:
            world.clock.sleep(0.5)  # long enough to see anything still moving
        if slow:
            panda = getattr(robot.arm._robot, "_impl", robot.arm._robot)  # behind the SDK double
            arm_signal_s = panda.stop_times_s[0] - signal_s
            still_s = max(0.0, probe.last_moving_wall_s - signal_s)
            print(
                f"{backend} {stage}: arm stop sent {arm_signal_s * 1000:.1f} ms after the "
                f"signal, all still {still_s * 1000:.0f} ms after it (wall time)"
            )
            assert arm_signal_s <= ARM_SIGNAL_BOUND_S, (
                f"{stage}: arm stopped {arm_signal_s:.3f} s late"
            )
            assert still_s <= SLOW_STOP_BOUND_S, (
                f"{stage}: moved until {still_s:.3f} s after the stop"
            )
        else:
            moving_s = max(0.0, probe.last_moving_s - stopped_s)
            print(f"{backend} {stage}: still {moving_s * 1000:.0f} ms of robot time after the stop")
            assert moving_s <= STOP_BOUND_S, f"{stage}: moved until {moving_s:.3f} s after the stop"
        with pytest.raises(RuntimeError, match="emergency-stopped"):
            robot.humanoid.set_velocity(0.1, 0.0, 0.0)
        with pytest.raises(RuntimeError, match="emergency-stopped"):
            robot.arm.move_to(HOME_CONFIGURATION)
        if stage in INTERRUPTED_WITH_ERROR:
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

        # The move's fast phase lasts a fraction of a second of wall time: a loaded machine
        # can poll past it, so the move is tried again (never a wait without an end).
        speed = 0.0
        for _attempt in range(5):
            thread = threading.Thread(target=move, daemon=True)
            thread.start()
            while thread.is_alive():
                speed = float(np.max(np.abs(world.panda.joint_velocities())))
                if speed >= 1.0:
                    break
                threading.Event().wait(0.002)
            if speed >= 1.0:
                break
            thread.join()
            world.panda.move_to(HOME_CONFIGURATION)
        world.robot.emergency_stop()
        thread.join(timeout=20.0)
        still_s = _still_after(world)
        print(f"arm at {speed:.2f} rad/s still after {still_s * 1000:.0f} ms of robot time")
        assert speed > 1.0 and still_s <= STOP_BOUND_S
        assert errors, "the interrupted move_to must raise"
