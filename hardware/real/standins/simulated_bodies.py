"""The simulated world behind the SDK stand-ins: the real backends drive the simulation.

:class:`SimulatedNaoBody` moves the simulated NAO for :class:`~hardware.real.standins.NaoqiStandin`
(walking, joint trajectories, hands, speech heard by the simulated helper);
:class:`SimulatedPanda` is a :class:`~hardware.real.standins.PandaStandin` whose joints are
the simulated Panda's; :func:`simulated_carmine` renders the wrist camera for
:class:`~hardware.real.standins.OpenNI2Standin`. :func:`robot_over_standins` puts the real
backends (:mod:`bearchair.hardware.real.nao`, :mod:`bearchair.hardware.real.panda`,
:mod:`bearchair.hardware.real.camera`) on top, so the mission runs through qi networking, panda-py's
call shapes and OpenNI's frames, with the simulation's clock, helper and judge.
"""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from bearchair.core.geometry import make_transform, rot_z
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Robot
from bearchair.hardware.real.standins import (
    FRANKA_HAND_F_T_EE,
    JointKeyframes,
    NaoqiStandin,
    OpenNI2Standin,
    PandaStandin,
    sdk_openni2,
    sdk_panda,
)

T_FLANGE_HAND = make_transform(rot_z(-math.pi / 4), np.zeros(3))
"""panda.urdf's ``panda_hand`` in the flange (``panda_link8``): -45 deg about z."""


class SimulatedNaoBody:
    """The simulated NAO behind the NAOqi stand-in's services.

    Args:
        world: a :class:`bearchair.hardware.sim.world.SimWorld`.
        boot_odometry: what NAOqi's odometry reads at the start (not zero, as after a boot).
    """

    def __init__(self, world: Any, boot_odometry: tuple[float, float, float] = (3.0, -1.0, 0.7)):
        self._world = world
        self._nao = world.nao
        self._clock = world.clock
        self.joints: dict[str, float] = {}
        self._start = self._nao.pose()
        self._boot = SE2Pose(*map(float, boot_odometry))
        self._walk_end_s: float | None = None
        self._lock = threading.Lock()
        self._clock.add_process(self._end_walk)

    def odometry(self) -> np.ndarray:
        # NAOqi's odometry: the walk since the start, carried from where the boot put it.
        return np.array(self._boot.compose(self._start.between(self._nao.pose())))

    def walk(self, velocity: np.ndarray, duration_s: float) -> None:
        with self._lock:
            self._nao.set_velocity(*map(float, velocity))
            self._walk_end_s = self._clock.now() + duration_s

    def _end_walk(self, now_s: float, dt_s: float) -> None:
        # A clock process: the walk command runs out in robot time, as on the NAO.
        if self._walk_end_s is not None and now_s >= self._walk_end_s:
            self._walk_end_s = None
            self._nao.set_velocity(0.0, 0.0, 0.0)

    def stop_walk(self) -> None:
        with self._lock:
            self._walk_end_s = None
            self._nao.set_velocity(0.0, 0.0, 0.0)
            self._nao.stop()

    def walking(self) -> bool:
        return self._walk_end_s is not None

    def play(self, keyframes: JointKeyframes, cancelled: threading.Event) -> None:
        names, angles, times = keyframes
        if any(joint_times != times[0] for joint_times in times):
            raise RuntimeError("the simulated NAO plays one time list for all joints")
        positions = np.array(angles, dtype=float).T
        self._nao.play_joint_trajectory(names, times[0], positions)

    def hand(self, hand: str, open_hand: bool, cancelled: threading.Event) -> None:
        self._nao.set_hands(open_hand)

    def posture(self, name: str, cancelled: threading.Event) -> None:
        """The simulated NAO already stands, carrying the bear."""

    def cancel_motions(self) -> None:
        self._nao.stop()

    def say(self, sentence: str) -> None:
        self._world.speaker.say(sentence)


class SimulatedPanda(PandaStandin):
    """panda-py's calls on the simulated Panda (base at the world origin)."""

    def __init__(self, world: Any) -> None:
        super().__init__("simulated")
        self._sim = world.panda

    def get_state(self) -> Any:
        state = super().get_state()
        q = self._sim.joint_positions()
        state.q = q.tolist()
        T_base_hand = self._sim.T_world_camera() @ np.linalg.inv(_t_hand_camera())
        O_T_EE = T_base_hand @ np.linalg.inv(T_FLANGE_HAND) @ FRANKA_HAND_F_T_EE
        state.O_T_EE = O_T_EE.T.reshape(-1).tolist()
        return state

    def get_pose(self) -> np.ndarray:
        return np.asarray(self.get_state().O_T_EE).reshape(4, 4).T

    def stop_motion(self) -> None:
        self._sim.emergency_stop()

    def _move(self, target: np.ndarray, speed_factor: float, success_threshold: float) -> bool:
        try:
            self._sim.move_to(target, timeout_s=30.0)
        except (RuntimeError, TimeoutError) as error:
            from bearchair.hardware.real.standins import ControlException

            self._last_error = ControlException(f"libfranka: Move command aborted: {error}")
            return False
        return True


def _t_hand_camera() -> np.ndarray:
    from bearchair.hardware.wrist_mount import T_HAND_CAMERA

    return T_HAND_CAMERA


def simulated_carmine(world: Any) -> OpenNI2Standin:
    """OpenNI frames rendered by the simulated wrist camera (one render per robot instant)."""
    cache: dict[str, Any] = {}
    lock = threading.Lock()

    def render(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        with lock:
            now = world.clock.now()
            if cache.get("stamp") != now:
                frame = world.panda.capture()
                depth_mm = np.round(np.nan_to_num(frame.depth_m) * 1000.0)
                cache.update(stamp=now, rgb=frame.rgb, depth=np.clip(depth_mm, 0, 65535))
            return cache["rgb"], cache["depth"].astype(np.uint16)

    return OpenNI2Standin(render=render, stamp_us=lambda: int(world.clock.now() * 1e6))


def robot_over_standins(world: Any, standin: NaoqiStandin) -> tuple[Robot, Any]:
    """The real backends on the stand-ins, the simulation behind them (not yet activated).

    Returns:
        (the robot, the qi session: close it when done).
    """
    from bearchair.hardware.real.camera import CarmineCamera
    from bearchair.hardware.real.nao import NaoHumanoid, NaoSpeaker, connect
    from bearchair.hardware.real.panda import PandaArm

    session = connect(standin.url)
    start = world.nao.pose()
    arm = PandaArm(
        sdk_panda(SimulatedPanda(world)),
        CarmineCamera(sdk_openni2(simulated_carmine(world)), intrinsics=world.panda.intrinsics),
        T_world_base=np.eye(4),
        T_flange_camera=T_FLANGE_HAND @ _t_hand_camera(),
    )
    robot = Robot(
        arm=arm,
        humanoid=NaoHumanoid(
            session, odom_origin=SE2Pose(start.x, start.y, start.theta), clock=world.clock
        ),
        speaker=NaoSpeaker(session),
        clock=world.clock,
        helper=world.helper,
        judge=world.judge,
    )
    return robot, session
