"""The real-robot backends against the SDK stand-ins (no robot needed).

The NAO tests talk to :class:`bearchair.hardware.real.standins.NaoqiStandin` over real ``qi``
networking (skipped without the ``nao`` extra): a wrong method name or argument type
raises there as on the robot. The arm and camera run against fakes built from
panda-py's and openni's signatures, checked against the installed SDKs when present.
"""

from __future__ import annotations

import contextlib
import inspect
import math
import threading
import time

import numpy as np
import pytest

from bearchair.core.errors import BackendUnavailable
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.interfaces import Humanoid, ScanningArm, Speaker
from bearchair.hardware.real import EmergencyStopped, import_sdk
from bearchair.hardware.real.camera import CarmineCamera
from bearchair.hardware.real.panda import JOINT_LIMITS_LOWER_RAD, ArmFault, PandaArm, into_walls
from bearchair.hardware.real.standins import (
    FRANKA_HAND_F_T_EE,
    OpenNI2Standin,
    PandaStandin,
    panda_flange_pose,
    sdk_openni2,
    sdk_panda,
    sdk_realsense,
)
from bearchair.skills.perception.views import SCAN_CONFIGURATIONS


def test_missing_sdk_names_the_extra_to_install():
    with pytest.raises(BackendUnavailable, match=r"pip install 'bearchair\[nao\]'"):
        import_sdk("not_a_robot_sdk_module", "bearchair[nao]")


# --- NAO over qi --------------------------------------------------------------------------


def _eventually(condition, timeout_s: float = 3.0) -> bool:
    """Polls ``condition``: async qi calls reach the stand-in a moment after they are sent."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.005)
    return condition()


@pytest.fixture
def naoqi():
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=4.0) as standin:
        yield standin


@pytest.fixture
def nao(naoqi):
    from bearchair.hardware.real.nao import NaoHumanoid, connect

    session = connect(naoqi.url)
    yield NaoHumanoid(session, odom_origin=SE2Pose(1.9, 0.0, math.pi))
    session.close()


def test_connecting_moves_nothing_and_activation_sets_up_carrying(naoqi, nao):
    assert isinstance(nao, Humanoid)
    state = nao.state()
    assert state == {
        "awake": False,
        "arm_swing": True,
        "autonomous_life": "solitary",
        "basic_awareness": True,
        "battery_percent": 87,
    }
    moving = {"wakeUp", "move", "moveTo", "angleInterpolation", "goToPosture", "setState"}
    moving |= {"setEnabled"}
    assert not moving & {name for _, name, _ in naoqi.calls}
    nao.activate()
    assert naoqi.called("setState") == [("disabled",)]
    assert naoqi.called("setEnabled") == [(False,)]
    assert naoqi.called("setMoveArmsEnabled") == [(False, False)]
    assert naoqi.called("closeHand") == [("LHand",), ("RHand",)]
    names, angles, speed = naoqi.called("angleInterpolationWithSpeed")[0]
    assert names[:2] == ["HeadYaw", "HeadPitch"] and "LShoulderPitch" in names
    assert len(angles) == len(names) and 0.0 < speed <= 1.0
    order = [name for _, name, _ in naoqi.calls]
    assert order.index("setState") < order.index("wakeUp") < order.index("goToPosture")


def test_odometry_counts_from_the_first_reading(naoqi, nao):
    # NAOqi's odometry reads (3, -1, 0.7) at the start: the pose must still be the start.
    pose = nao.pose()
    assert (pose.x, pose.y) == pytest.approx((1.9, 0.0), abs=1e-6)
    assert pose.theta == pytest.approx(math.pi, abs=1e-6) or pose.theta == pytest.approx(
        -math.pi, abs=1e-6
    )
    nao.activate()
    boot = naoqi.body.odometry()
    nao.set_velocity(0.1, 0.0, 0.0)
    time.sleep(0.1)
    nao.stop()
    walked_m = float(np.linalg.norm(naoqi.body.odometry()[:2] - boot[:2]))
    pose = nao.pose()
    # Forward from a start facing -x: toward -x by what NAOqi's odometry walked.
    assert walked_m > 0.01
    assert pose.x == pytest.approx(1.9 - walked_m, abs=1e-6) and pose.y == pytest.approx(
        0.0, abs=1e-6
    )


@pytest.mark.slow
def test_walking_is_a_latched_move_that_the_heartbeat_ends(naoqi, nao):
    from bearchair.hardware.real.nao import HEARTBEAT_PERIOD_S

    nao.activate()
    nao.set_velocity(1.0, 0.0, -3.0)  # clipped to 0.1 m/s and 0.5 rad/s
    assert naoqi.called("move")[-1] == pytest.approx((0.1, 0.0, -0.5))
    assert not naoqi.called("moveTo")
    # The controller keeps commanding: the walk goes on past two heartbeat periods.
    for _ in range(8):
        time.sleep(HEARTBEAT_PERIOD_S / 2)
        nao.set_velocity(0.05, 0.0, 0.0)
    assert naoqi.motion.walking() and nao.watchdog.fired == 0
    # The controller falls silent: two missed periods and the watchdog calls stopMove.
    silent = time.monotonic()
    assert _eventually(lambda: not naoqi.motion.walking(), timeout_s=2.0)
    assert time.monotonic() - silent < 2.25 * HEARTBEAT_PERIOD_S + 0.1
    assert nao.watchdog.fired == 1 and naoqi.called("stopMove")


def test_a_refused_walking_command_raises(naoqi, nao):
    from bearchair.core.errors import BackendError

    # Not awake: NAOqi refuses move(); the backend checks its result and says so.
    with pytest.raises(BackendError, match="not awake"):
        nao.set_velocity(0.1, 0.0, 0.0)


def test_trajectory_is_one_cancellable_angle_interpolation(naoqi, nao):
    nao.activate()
    positions = -np.array([[0.0, 0.1], [0.2, 0.3], [0.4, 0.5]])
    nao.play_joint_trajectory(["LHipPitch", "RHipPitch"], [0.0, 0.4, 0.8], positions)
    names, angles, times, absolute = naoqi.called("angleInterpolation")[-1]
    assert names == ["LHipPitch", "RHipPitch"] and absolute is True
    assert angles == [[-0.2, -0.4], [-0.3, -0.5]] and times == [[0.4, 0.8], [0.4, 0.8]]
    assert naoqi.motion.joints["RHipPitch"] == pytest.approx(-0.5)
    with pytest.raises(ValueError, match="does not match"):
        nao.play_joint_trajectory(["LHipPitch"], [1.0], positions)


@pytest.mark.parametrize("motion", ["trajectory", "walk", "hands"])
def test_emergency_stop_ends_every_nao_motion(naoqi, nao, motion):
    nao.activate()
    errors: list[BaseException] = []

    def run() -> None:
        try:
            if motion == "trajectory":
                nao.play_joint_trajectory(["LKneePitch"], [20.0], np.array([[1.0]]))
            elif motion == "walk":
                for _ in range(100):
                    nao.set_velocity(0.1, 0.0, 0.0)
                    time.sleep(0.02)
            else:
                for _ in range(100):
                    nao.set_hands(True)
        except EmergencyStopped as error:
            errors.append(error)

    worker = threading.Thread(target=run)
    worker.start()
    time.sleep(0.15)
    stopped_at = time.monotonic()
    nao.emergency_stop()
    worker.join(5.0)
    assert not worker.is_alive() and time.monotonic() - stopped_at < 0.5
    assert errors, "the running motion must end with EmergencyStopped"
    assert not naoqi.motion.walking() and naoqi.called("stopMove")
    kills = [set(joints) for (joints,) in naoqi.called("killTasksUsingResources")]
    # Only the joints of the motions that ran are freed; the walk is left to stopMove.
    expected = {"trajectory": [{"LKneePitch"}], "walk": [], "hands": [{"LHand", "RHand"}]}
    assert kills == expected[motion] or (motion == "hands" and kills == [{"LHand"}])
    assert naoqi.fell == ""
    if motion == "trajectory":
        assert "LKneePitch" not in naoqi.motion.joints  # cancelled, never completed
    with pytest.raises(EmergencyStopped):
        nao.set_velocity(0.1, 0.0, 0.0)


def test_emergency_stop_waits_for_the_walk_to_end_before_killing(naoqi, nao):
    """A stop mid-walk with a head motion running: the head is freed only once
    ``moveIsActive()`` reads false, so the walk's legs are never killed mid-step."""
    naoqi.body.stop_runout_s = 0.3 * naoqi.time_scale  # 0.3 s on both feet after stopMove
    nao.activate()
    nao.set_velocity(0.1, 0.0, 0.0)
    head = threading.Thread(
        target=_ignore_stop,
        args=(lambda: nao.play_joint_trajectory(["HeadYaw"], [5.0], np.array([[0.5]])),),
    )
    head.start()
    assert _eventually(lambda: naoqi.called("angleInterpolation"))
    nao.emergency_stop()
    head.join(3.0)
    order = [name for _, name, _ in naoqi.calls]
    stop = order.index("stopMove")
    kill = order.index("killTasksUsingResources")
    assert stop < order.index("moveIsActive", stop) < kill and naoqi.called(
        "killTasksUsingResources"
    ) == [(["HeadYaw"],)]
    assert naoqi.fell == ""


def _ignore_stop(job) -> None:
    with contextlib.suppress(EmergencyStopped):
        job()


def test_speech_goes_through_text_to_speech(naoqi):
    from bearchair.hardware.real.nao import NaoSpeaker, connect

    session = connect(naoqi.url)
    speaker = NaoSpeaker(session)
    assert isinstance(speaker, Speaker)
    speaker.say("hello")
    assert naoqi.called("say") == [("hello",)]


def test_the_standin_refuses_what_naoqi_would(naoqi):
    from bearchair.hardware.real.nao import connect

    session = connect(naoqi.url)
    motion = session.service("ALMotion")
    with pytest.raises(RuntimeError, match="did not match"):
        motion.moveTo(0.1, 0.0)
    with pytest.raises(AttributeError):
        motion.walkTo(0.1, 0.0, 0.0)
    with pytest.raises(RuntimeError, match="not awake"):
        motion.moveTo(0.1, 0.0, 0.0)


def test_unreachable_nao_fails_fast_with_its_url():
    pytest.importorskip("qi")
    from bearchair.hardware.real.nao import connect

    started = time.monotonic()
    with pytest.raises(BackendUnavailable, match=r"tcp://127\.0\.0\.1:9"):
        connect("tcp://127.0.0.1:9", timeout_s=2.0)
    assert time.monotonic() - started < 5.0


# --- Panda --------------------------------------------------------------------------------


def _arm(panda: PandaStandin | None = None, camera=None, **options) -> PandaArm:
    """The backend over the fakes, each behind the installed SDK's own classes."""
    camera = camera or CarmineCamera(sdk_openni2(OpenNI2Standin()))
    return PandaArm(
        sdk_panda(panda or PandaStandin("standin")), camera, np.eye(4), np.eye(4), **options
    )


def test_fake_panda_matches_the_installed_sdk():
    panda_py = pytest.importorskip("panda_py")
    for name in ("get_state", "get_pose", "get_robot", "recover", "raise_error", "stop_controller"):
        assert hasattr(panda_py.Panda, name)
    doc = panda_py.Panda.move_to_joint_position.__doc__
    for parameter in inspect.signature(PandaStandin.move_to_joint_position).parameters:
        if parameter not in ("self", "positions"):
            assert f"{parameter}:" in doc, parameter
    assert "speed_factor: typing.SupportsFloat | typing.SupportsIndex = 0.2" in doc
    for name in ("stop", "read_once", "automatic_error_recovery", "server_version"):
        assert hasattr(panda_py.libfranka.Robot, name)
    for name in ("O_T_EE", "F_T_EE", "q", "robot_mode", "current_errors"):
        assert hasattr(panda_py.libfranka.RobotState, name)
    assert set(panda_py.libfranka.RobotMode.__members__) >= {"kReflex", "kIdle", "kUserStopped"}


def test_camera_pose_uses_the_flange_not_o_t_ee():
    panda = PandaStandin("standin")
    arm = _arm(panda)
    assert isinstance(arm, ScanningArm)
    frame = arm.capture()
    np.testing.assert_allclose(frame.T_world_camera, panda_flange_pose(panda.q), atol=1e-12)
    # O_T_EE is 10.34 cm further along the flange's z axis.
    offset = np.linalg.norm(panda.get_pose()[:3, 3] - frame.T_world_camera[:3, 3])
    assert offset == pytest.approx(np.linalg.norm(FRANKA_HAND_F_T_EE[:3, 3]))


def test_scan_view_inside_the_joint_wall_is_moved_to_its_edge():
    assert SCAN_CONFIGURATIONS[4][1] - JOINT_LIMITS_LOWER_RAD[1] < 0.01  # the 9 mrad view
    target, notes = into_walls(np.asarray(SCAN_CONFIGURATIONS[4]))
    assert notes and notes[0].startswith("joint 2")
    assert target[1] == pytest.approx(JOINT_LIMITS_LOWER_RAD[1] + 0.09)
    with pytest.raises(ValueError, match="joint 4"):
        into_walls(np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]))


def test_arm_moves_and_reports_libfranka_faults_without_recovering():
    panda = PandaStandin("standin")
    arm = _arm(panda)
    target = np.asarray(SCAN_CONFIGURATIONS[0])
    arm.move_to(target)
    np.testing.assert_allclose(arm.joint_positions(), target, atol=1e-9)
    panda.inject_reflex("cartesian_reflex")
    with pytest.raises(ArmFault, match=r"kReflex.*cartesian_reflex"):
        arm.move_to(SCAN_CONFIGURATIONS[1])
    assert not [call for call in panda.calls if "recovery" in call[0] or call[0] == "recover"]


def test_arm_timeout_is_honoured_and_stops_the_arm():
    panda = PandaStandin("standin")
    panda.time_scale = 0.05  # a slow arm: the move would take many seconds
    arm = _arm(panda)
    started = time.monotonic()
    with pytest.raises(TimeoutError, match="stopped"):
        arm.move_to(SCAN_CONFIGURATIONS[2], timeout_s=0.3)
    assert time.monotonic() - started < 1.0
    assert ("Robot.stop", ()) in panda.calls


def test_emergency_stop_preempts_a_running_arm_move():
    panda = PandaStandin("standin")
    panda.time_scale = 0.2
    arm = _arm(panda)
    errors: list[BaseException] = []

    def run() -> None:
        try:
            arm.move_to(SCAN_CONFIGURATIONS[2])
        except EmergencyStopped as error:
            errors.append(error)

    worker = threading.Thread(target=run)
    worker.start()
    time.sleep(0.2)
    arm.emergency_stop()
    worker.join(2.0)
    assert not worker.is_alive() and errors
    assert ("Robot.stop", ()) in panda.calls
    q = arm.joint_positions()
    time.sleep(0.05)
    np.testing.assert_array_equal(arm.joint_positions(), q)
    with pytest.raises(EmergencyStopped):
        arm.move_to(SCAN_CONFIGURATIONS[0])


# --- Carmine ------------------------------------------------------------------------------


def test_carmine_sets_640x480_depth_in_mm_registered_and_synchronised():
    openni = OpenNI2Standin()
    camera = CarmineCamera(sdk_openni2(openni))
    rgb, depth_m = camera.read()
    assert rgb.shape == (480, 640, 3) and depth_m.shape == (480, 640)
    assert depth_m.dtype == np.float32 and np.all(depth_m == pytest.approx(1.0))
    assert rgb[0, 0].tolist() == [128, 128, 128]  # copied before the frame was released
    assert openni.registration == openni.IMAGE_REGISTRATION_DEPTH_TO_COLOR and openni.sync
    assert camera.mode()["depth"].startswith("640x480")


def test_carmine_library_folder_and_missing_device_are_one_line_errors():
    with pytest.raises(BackendUnavailable, match="openni_library_dir"):
        CarmineCamera(OpenNI2Standin(library_dir="/usr/lib/x86_64-linux-gnu"))
    CarmineCamera(
        OpenNI2Standin(library_dir="/usr/lib/x86_64-linux-gnu"),
        library_dir="/usr/lib/x86_64-linux-gnu",
    )
    with pytest.raises(BackendUnavailable, match="no OpenNI2 camera found"):
        CarmineCamera(OpenNI2Standin(devices=0))


def test_fake_openni_matches_the_installed_binding():
    openni2 = pytest.importorskip("openni.openni2")
    for name in ("initialize", "Device", "PIXEL_FORMAT_DEPTH_1_MM", "PIXEL_FORMAT_RGB888"):
        assert hasattr(openni2, name)
    assert "IMAGE_REGISTRATION_DEPTH_TO_COLOR" in dir(openni2)
    for name in (
        "open_any",
        "create_depth_stream",
        "create_color_stream",
        "is_image_registration_mode_supported",
        "set_image_registration_mode",
        "set_depth_color_sync_enabled",
    ):
        assert hasattr(openni2.Device, name), name
    for name in ("configure_mode", "get_video_mode", "start", "stop", "read_frame"):
        assert hasattr(openni2.VideoStream, name), name
    for name in ("get_buffer_as_uint16", "get_buffer_as_uint8"):
        assert hasattr(openni2.VideoFrame, name), name
    assert list(inspect.signature(openni2.VideoStream.configure_mode).parameters) == [
        "self",
        "width",
        "height",
        "fps",
        "pixel_format",
    ]


# --- RealSense ----------------------------------------------------------------------------


def test_realsense_aligns_depth_to_colour_in_metres():
    from bearchair.hardware.real.camera import RealSenseCamera
    from bearchair.hardware.real.standins import RealSenseStandin

    rs = RealSenseStandin(depth_scale_m=0.0001)  # a D405-like 0.1 mm unit
    camera = RealSenseCamera(sdk_realsense(rs))
    rgb, depth_m = camera.read()
    assert rgb.shape == (480, 640, 3) and depth_m.dtype == np.float32
    valid = depth_m > 0.0  # alignment leaves no depth where the depth imager did not see
    assert np.all(depth_m[valid] == pytest.approx(1.0)) and valid[:, :600].all()
    assert rs.aligned_to == rs.stream.color
    assert (rs.stream.depth, 640, 480, rs.format.z16, 30) in rs.enabled
    assert camera.intrinsics.fx == 615.0 and "0.1 mm" in camera.mode()["depth"]
    with pytest.raises(BackendUnavailable, match="no RealSense camera"):
        RealSenseCamera(RealSenseStandin(devices=0))


def test_fake_realsense_matches_the_installed_sdk():
    rs = pytest.importorskip("pyrealsense2")
    assert {"depth", "color"} <= set(dir(rs.stream)) and {"z16", "rgb8"} <= set(dir(rs.format))
    for owner, name in (
        (rs.config, "enable_stream"),
        (rs.config, "enable_device"),
        (rs.pipeline, "start"),
        (rs.pipeline, "wait_for_frames"),
        (rs.pipeline, "stop"),
        (rs.align, "process"),
        (rs.device, "first_depth_sensor"),
        (rs.depth_sensor, "get_depth_scale"),
        (rs.pipeline_profile, "get_stream"),
        (rs.stream_profile, "as_video_stream_profile"),
        (rs.video_stream_profile, "get_intrinsics"),
        (rs.composite_frame, "get_depth_frame"),
        (rs.composite_frame, "get_color_frame"),
    ):
        assert hasattr(owner, name), f"{owner.__name__}.{name}"
    assert "width: int, height: int, format: pyrealsense2.pyrealsense2.format, framerate: int" in (
        rs.config.enable_stream.__doc__
    )


# --- connects that never hang -------------------------------------------------------------


def _ends_within(job, bound_s: float) -> BaseException | None:
    """Runs ``job`` in a daemon thread: what it raised, or a failure if still running."""
    outcome: list[BaseException | None] = []

    def run() -> None:
        try:
            job()
            outcome.append(None)
        except BaseException as error:
            outcome.append(error)

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(bound_s)
    assert not worker.is_alive(), f"still waiting after {bound_s} s: it hangs"
    return outcome[0]


def test_connecting_to_a_silent_nao_ends_in_its_timeout_naming_it():
    pytest.importorskip("qi")
    from bearchair.hardware.real.nao import connect
    from tests.helpers.silent_peers import silent_peer

    with silent_peer() as (host, port):
        started = time.monotonic()
        error = _ends_within(lambda: connect(f"tcp://{host}:{port}", timeout_s=0.3), 3.0)
    assert isinstance(error, BackendUnavailable) and f"NAO at tcp://{host}:{port}" in str(error)
    assert time.monotonic() - started < 1.0


def test_connecting_to_a_silent_panda_ends_in_its_timeout_naming_it():
    pytest.importorskip("panda_py")
    from tests.helpers.silent_peers import silent_panda

    with silent_panda() as host:
        started = time.monotonic()
        error = _ends_within(
            lambda: PandaArm.connect(host, np.eye(4), np.eye(4), timeout_s=0.3), 3.0
        )
    assert isinstance(error, BackendUnavailable) and f"the Panda at {host}" in str(error)
    assert time.monotonic() - started < 1.0


def test_a_silent_camera_read_ends_in_its_timeout_naming_it():
    camera = CarmineCamera(OpenNI2Standin(silent=True), timeout_s=0.2)
    error = _ends_within(camera.read, 3.0)
    assert isinstance(error, BackendUnavailable) and "the Carmine sent no depth frame" in str(error)


def test_an_ordinary_stop_ends_the_walk_with_stopmove_alone(naoqi, nao):
    """A walk that ends (or fails) is stopped with ``stopMove``: nothing is killed, so the
    walk's leg tasks end on both feet and the other motions go on."""
    naoqi.body.stop_runout_s = 0.3 * naoqi.time_scale  # 0.3 s on both feet after stopMove
    nao.activate()
    nao.set_velocity(0.1, 0.0, 0.0)
    nao.stop()
    assert naoqi.called("stopMove") and not naoqi.called("killTasksUsingResources")
    assert naoqi.fell == ""
    nao.set_velocity(0.1, 0.0, 0.0)  # not latched: the NAO walks again
    nao.stop()


def test_the_naoqi_standin_counts_killing_the_legs_mid_walk_as_a_fall(naoqi):
    from bearchair.hardware.real.nao import connect

    session = connect(naoqi.url)
    motion = session.service("ALMotion")
    motion.wakeUp()
    motion.killTasksUsingResources(["LLeg"])  # standing still: nothing falls
    assert naoqi.fell == ""
    motion.move(0.1, 0.0, 0.0)
    motion.killTasksUsingResources(["HeadYaw"])  # not a leg: the walk goes on
    assert naoqi.fell == "" and naoqi.motion.walking()
    motion.killTasksUsingResources(["LLeg"])
    assert "mid-walk" in naoqi.fell
    session.close()


def test_the_naoqi_standins_slow_link_answers_every_call_late_and_together():
    pytest.importorskip("qi")
    from bearchair.hardware.real.nao import connect
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(call_latency_s=0.3) as naoqi:
        session = connect(naoqi.url)
        motion = session.service("ALMotion")
        started = time.monotonic()
        futures = [motion.robotIsWakeUp(_async=True) for _ in range(3)]
        answers = [future.value() for future in futures]
        took_s = time.monotonic() - started
        session.close()
    assert answers == [False, False, False]
    # Each answered 0.3 s late, the three side by side (not one after the other).
    assert 0.3 <= took_s < 0.85, took_s


def test_the_nao_stop_returns_within_its_bounds_on_a_link_that_stopped_answering():
    """A half-open Wi-Fi link: every NAOqi call goes unanswered for seconds. The stop's
    calls are sent without waiting and each is waited for at most STOP_CALL_TIMEOUT_S,
    so the stop returns (and the other devices' stops are not held) in about a second."""
    pytest.importorskip("qi")
    from bearchair.hardware.real.nao import STOP_CALL_TIMEOUT_S, NaoHumanoid, connect
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=4.0) as naoqi:
        session = connect(naoqi.url)
        nao = NaoHumanoid(session)
        nao.activate()
        nao.set_velocity(0.1, 0.0, 0.0)
        naoqi.call_latency_s = 5.0  # from here on nothing is answered for 5 s
        started = time.monotonic()
        nao.emergency_stop()
        took_s = time.monotonic() - started
        session.close()
    assert took_s < 4 * STOP_CALL_TIMEOUT_S + 0.5, f"the stop took {took_s:.2f} s"
