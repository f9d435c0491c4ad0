"""The second look at the real-robot backends (issue 30): each defect has its test here
or in test_real_backends / test_emergency_stop / test_check_hardware_silent.

Camera mirroring and intrinsics, Panda timeouts, collision thresholds, payload and FR3
limits, a move stopped by Ctrl-C, monitoring during a run, HeadYaw in the tag's heading,
simulation-only options refused with ``--robots``, NAOqi's missing services as one line,
the SDK doubles and NAOqi's documented method table, and ``check-hardware --walk``.
"""

from __future__ import annotations

import json
import math
import os
import signal
import threading
import time

import numpy as np
import pytest

from bearchair.core.errors import BackendUnavailable
from bearchair.core.se2 import SE2Pose
from bearchair.executive.cli import main
from bearchair.hardware.real.camera import CARMINE_INTRINSICS, CarmineCamera
from bearchair.hardware.real.panda import COLLISION_TORQUE_NM, PandaArm, into_walls
from bearchair.hardware.real.standins import OpenNI2Standin, PandaStandin, sdk_openni2, sdk_panda
from tests.helpers.cells import standin_cell_file


def _arm(panda: PandaStandin, **options) -> PandaArm:
    camera = CarmineCamera(sdk_openni2(OpenNI2Standin()))
    return PandaArm(sdk_panda(panda), camera, np.eye(4), np.eye(4), **options)


# --- the camera ---------------------------------------------------------------------------


def test_the_carmine_turns_mirroring_off_reads_it_back_and_refuses_a_mirrored_stream():
    openni = OpenNI2Standin()
    camera = CarmineCamera(sdk_openni2(openni))
    assert camera.mode()["mirroring"] == "off"
    with pytest.raises(BackendUnavailable, match="stays mirrored"):
        CarmineCamera(sdk_openni2(OpenNI2Standin(mirroring_stuck=True)))


def test_carmine_frames_are_not_mirrored():
    def render(width, height):
        rgb = np.zeros((height, width, 3), np.uint8)
        rgb[:, : width // 4] = 255  # a white band on the left
        return rgb, np.full((height, width), 1000, np.uint16)

    rgb, _ = CarmineCamera(sdk_openni2(OpenNI2Standin(render=render))).read()
    assert rgb[:, :10].min() == 255 and rgb[:, -10:].max() == 0


def test_carmine_intrinsics_come_from_the_stream_or_the_cell_file():
    from bearchair.hardware.real.standins.openni import COLOUR_FOV_RAD

    camera = CarmineCamera(sdk_openni2(OpenNI2Standin()))
    expected = 320.0 / math.tan(COLOUR_FOV_RAD[0] / 2.0)
    assert camera.intrinsics.fx == pytest.approx(expected) and camera.intrinsics.fx != 570.3
    assert "field of view" in camera.mode()["intrinsics"]
    calibrated = CARMINE_INTRINSICS._replace(fx=561.2, fy=560.8, cx=322.0, cy=241.5)
    camera = CarmineCamera(sdk_openni2(OpenNI2Standin()), intrinsics=calibrated)
    assert camera.intrinsics == calibrated and "cell file" in camera.mode()["intrinsics"]


def test_the_cell_file_takes_checked_camera_intrinsics():
    from bearchair.executive.cell_config import CellConfigError, parse_cell_config

    raw = {
        "nao_url": "tcp://nao.local:9559",
        "panda_host": "standin",
        "T_world_base": np.eye(4).tolist(),
        "T_flange_camera": np.eye(4).tolist(),
        "nao_start_x_m": 1.9,
        "nao_start_y_m": 0.0,
        "nao_start_yaw_rad": 3.14,
    }
    intrinsics = {"fx_px": 561.2, "fy_px": 560.8, "cx_px": 322.0, "cy_px": 241.5}
    cell = parse_cell_config({**raw, "camera_intrinsics": intrinsics})
    assert cell.camera_intrinsics is not None and cell.camera_intrinsics.fx == 561.2
    assert cell.to_json()["camera_intrinsics"] == intrinsics
    with pytest.raises(CellConfigError, match="fx_px"):
        parse_cell_config({**raw, "camera_intrinsics": {**intrinsics, "fx_px": 5612.0}})


def test_dropping_the_realsense_alignment_is_seen():
    from bearchair.hardware.real.camera import RealSenseCamera
    from bearchair.hardware.real.standins import RealSenseStandin, sdk_realsense

    def render(width, height):
        rgb = np.zeros((height, width, 3), np.uint8)
        rgb[:, width // 2 :] = 255
        depth = np.full((height, width), 800, np.uint16)
        depth[:, width // 2 :] = 1200  # the depth edge is the colour edge
        return rgb, depth

    camera = RealSenseCamera(sdk_realsense(RealSenseStandin(render=render)))
    rgb, depth_m = camera.read()
    edge = int(np.argmax(rgb[0, :, 0] > 0))
    assert depth_m[0, edge - 1] == pytest.approx(0.8) and depth_m[0, edge] == pytest.approx(1.2)


# --- the Panda ----------------------------------------------------------------------------


class _FastClock:
    """Robot time twenty times the wall's (the fake arm runs as fast)."""

    def now(self) -> float:
        return time.monotonic() * 20.0


def test_a_slow_move_gets_the_time_its_planned_duration_needs():
    panda = PandaStandin("standin")
    panda.time_scale = 20.0
    arm = _arm(panda, speed_factor=0.1, clock=_FastClock())
    target = np.asarray(panda.q) + np.array([2.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert arm.planned_duration_s(target) > 10.0  # the old fixed timeout would stop it
    arm.move_to(target)
    np.testing.assert_allclose(arm.joint_positions(), target, atol=1e-9)


def test_activation_sets_collision_thresholds_and_the_camera_payload():
    panda = PandaStandin("standin")
    T_flange_camera = np.eye(4)
    T_flange_camera[:3, 3] = [0.065, 0.0, 0.02]
    arm = PandaArm(sdk_panda(panda), CarmineCamera(OpenNI2Standin()), np.eye(4), T_flange_camera)
    arm.activate()
    assert panda.collision_thresholds is not None
    assert panda.collision_thresholds[0] == list(COLLISION_TORQUE_NM)
    assert panda.load is not None
    mass, centre, inertia = panda.load
    assert mass == pytest.approx(0.16) and centre == pytest.approx([0.065, 0.0, 0.02])
    assert len(inertia) == 9 and inertia[0] > 0.0


def test_the_fr3s_limits_come_from_the_robot():
    panda = PandaStandin("standin")
    panda.model = "fr3"
    arm = _arm(panda)
    assert arm.joint_limits[0][5] == pytest.approx(0.5445)
    target = np.array([0.0, 0.0, 0.0, -1.5, 0.0, 0.3, 0.0])  # fine on the FER
    into_walls(target)
    with pytest.raises(ValueError, match="joint 6"):
        arm.move_to(target)


@pytest.fixture
def python_ctrl_c():
    """Python's own SIGINT handler for the test: a shell that starts pytest in the
    background without job control leaves SIGINT ignored, and Python keeps it so."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_during_a_move_stops_the_arm(python_ctrl_c):
    panda = PandaStandin("standin")
    panda.time_scale = 0.2  # a move of many seconds
    arm = _arm(panda)
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        arm.move_to(np.asarray(panda.q) + 1.0)
    assert ("Robot.stop", ()) in panda.calls


def test_a_backend_line_reading_what_only_the_fake_has_fails():
    arm = _arm(PandaStandin("standin"))
    with pytest.raises(AttributeError, match="the SDK lacks it"):
        arm._robot.stop_motion()  # the fake's own hook, not panda-py's
    with pytest.raises(TypeError, match="the SDK takes"):
        arm._robot.move_to_joint_position(arm.joint_positions(), speedfactor=0.1)
    with pytest.raises(AttributeError, match="the SDK lacks it"):
        _ = arm._robot.get_state().mode  # RobotState has robot_mode, not mode


# --- the NAO ------------------------------------------------------------------------------


@pytest.fixture
def naoqi():
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=4.0) as standin:
        yield standin


def _nao(naoqi):
    from bearchair.hardware.real.nao import NaoHumanoid, connect

    return NaoHumanoid(connect(naoqi.url), odom_origin=SE2Pose(1.9, 0.0, math.pi))


def test_head_yaw_is_read_back_into_the_tags_heading(naoqi):
    from bearchair.behaviours.tracking import locate_torso
    from bearchair.hardware.interfaces import Robot

    nao = _nao(naoqi)
    naoqi.body.joints["HeadYaw"] = 0.2  # the head turned (a bump, low stiffness)
    assert nao.head_yaw_rad() == pytest.approx(0.2)

    class Skills:
        def locate_humanoid(self, arm):
            return SE2Pose(1.0, 0.5, 1.0)  # the tag, on the head, reads 1.0 rad

    robot = Robot(arm=None, humanoid=nao, speaker=None, clock=None)  # type: ignore[arg-type]
    torso = locate_torso(Skills(), robot)  # type: ignore[arg-type]
    assert torso is not None and torso.theta == pytest.approx(0.8)


@pytest.mark.parametrize(
    ("fault", "reason"),
    [
        ("battery", "battery is at 5 %"),
        ("fall", "no longer standing"),
        ("hot", "LKneePitch is hot"),
    ],
)
def test_monitoring_stops_the_robots_and_names_the_reason(naoqi, fault, reason):
    from bearchair.hardware.interfaces import Robot
    from bearchair.hardware.real import RobotFault
    from bearchair.hardware.real.monitor import RobotMonitor

    nao = _nao(naoqi)
    nao.activate()
    panda = PandaStandin("standin")
    robot = Robot(arm=_arm(panda), humanoid=nao, speaker=None, clock=None)  # type: ignore[arg-type]
    monitor = RobotMonitor(robot, period_s=0.05).start()
    time.sleep(0.2)
    monitor.check()  # healthy so far
    if fault == "battery":
        naoqi.battery_percent = 5
    elif fault == "fall":
        naoqi.posture_family = "LyingBelly"
    else:
        naoqi.memory["Device/SubDeviceList/LKneePitch/Temperature/Sensor/Status"] = 1
    deadline = time.monotonic() + 3.0
    while monitor.reason is None and time.monotonic() < deadline:
        time.sleep(0.02)
    monitor.close()
    with pytest.raises(RobotFault, match=reason):
        monitor.check()
    assert not naoqi.called("stopMove")  # the runner stops the robots, at the next tick


def test_the_panda_in_reflex_stops_a_run(naoqi):
    from bearchair.hardware.interfaces import Robot
    from bearchair.hardware.real.monitor import RobotMonitor

    panda = PandaStandin("standin")
    robot = Robot(arm=_arm(panda), humanoid=_nao(naoqi), speaker=None, clock=None)  # type: ignore[arg-type]
    monitor = RobotMonitor(robot, period_s=0.05).start()
    panda.inject_reflex("cartesian_reflex")
    deadline = time.monotonic() + 3.0
    while monitor.reason is None and time.monotonic() < deadline:
        time.sleep(0.02)
    monitor.close()
    assert monitor.reason is not None and "kReflex" in monitor.reason


def test_a_missing_naoqi_service_is_one_line_naming_it():
    pytest.importorskip("qi")
    from bearchair.hardware.real.nao import NaoHumanoid, connect
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(without=("ALBattery",)) as naoqi:
        nao = NaoHumanoid(connect(naoqi.url))
        with pytest.raises(BackendUnavailable, match="ALBattery") as caught:
            nao.state()
    assert "\n" not in str(caught.value)


def test_the_naoqi_standin_serves_only_documented_methods_with_the_naos_joints(naoqi):
    from bearchair.hardware.real.nao import connect
    from bearchair.hardware.real.standins.naoqi_model import documented, naoqi_api

    api = naoqi_api()
    assert "doc.aldebaran.com/2-8" in api["source"]
    assert api["services"]["ALMotion"]["moveTo"]["blocking"] is True
    assert api["services"]["ALMotion"]["move"]["blocking"] is False
    with pytest.raises(KeyError, match=r"not in NAOqi 2\.8"):
        documented("ALMotion", "walkTo")
    session = connect(naoqi.url)
    motion = session.service("ALMotion")
    motion.wakeUp()
    with pytest.raises(RuntimeError, match="not a NAO joint"):
        motion.angleInterpolation(["LKnee"], [[0.5]], [[1.0]], True)
    with pytest.raises(RuntimeError, match="outside"):
        motion.angleInterpolation(["LKneePitch"], [[57.3]], [[1.0]], True)  # degrees
    with pytest.raises(RuntimeError):
        motion.moveTo(0.1, 0.0)  # NAOqi's signature has three floats


def test_naoqis_moveto_blocks_and_a_second_motion_on_held_joints_is_postponed(naoqi):
    from bearchair.hardware.real.nao import connect

    session = connect(naoqi.url)
    motion = session.service("ALMotion")
    motion.wakeUp()
    started = time.monotonic()
    motion.moveTo(0.04, 0.0, 0.0)  # 0.4 s of robot time at 0.1 m/s, 4x faster
    assert time.monotonic() - started >= 0.09
    sent = time.monotonic()
    first = motion.angleInterpolation(["HeadYaw"], [[0.3]], [[0.8]], True, _async=True)
    while not naoqi.called("angleInterpolation"):  # arrived, then holds HeadYaw
        time.sleep(0.005)
    time.sleep(0.05)
    second = motion.angleInterpolation(["HeadYaw"], [[-0.3]], [[0.8]], True, _async=True)
    first.wait()
    second.wait()
    # 0.2 s of wall time each: one after the other, not together.
    assert time.monotonic() - sent >= 0.39
    assert naoqi.motion.joints["HeadYaw"] == pytest.approx(-0.3)


# --- the command line -----------------------------------------------------------------------


@pytest.mark.parametrize("option", [["--placement", "inaccessible"], ["--helper", "obeys"]])
def test_simulation_options_with_robots_are_refused(tmp_path, capsys, option):
    cell = standin_cell_file(tmp_path, "tcp://127.0.0.1:9")
    status = main(["run", "--robots", str(cell), *option, "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2 and f"{option[0]} is for the simulated world" in err


def test_mute_with_robots_keeps_the_nao_silent(naoqi):
    from bearchair.executive.cell_config import parse_cell_config
    from bearchair.hardware.real.robots import connect_robots
    from bearchair.hardware.speech import TextToSpeech

    raw = json.loads(_cell_text(naoqi.url))
    robot = connect_robots(parse_cell_config(raw), mute=True)
    assert isinstance(robot.speaker, TextToSpeech)
    robot.speaker.say("hello")
    assert not naoqi.called("say")


def test_run_with_robots_passes_mute_on(tmp_path, capsys, monkeypatch):
    from bearchair.hardware.real import robots

    asked: list[bool] = []

    def connect_robots(cell, mute=False):
        asked.append(mute)
        raise BackendUnavailable("no robots in this test")

    monkeypatch.setattr(robots, "connect_robots", connect_robots)
    cell = standin_cell_file(tmp_path, "tcp://127.0.0.1:9")
    status = main(["run", "--robots", str(cell), "--mute", "--out", str(tmp_path / "out")])
    assert status == 2 and asked == [True], capsys.readouterr().err


def _cell_text(nao_url: str) -> str:
    return json.dumps(
        {
            "nao_url": nao_url,
            "panda_host": "standin",
            "T_world_base": np.eye(4).tolist(),
            "T_flange_camera": np.eye(4).tolist(),
            "nao_start_x_m": 1.9,
            "nao_start_y_m": 0.0,
            "nao_start_yaw_rad": 3.14159,
        }
    )


@pytest.mark.parametrize(
    ("runout_s", "queue_s", "failed"),
    [(0.0, 0.0, ""), (1.0, 0.0, "run-out"), (0.0, 1.5, "commands: queue")],
)
@pytest.mark.slow
def test_check_hardware_walk_measures_the_run_out_and_refuses_an_unsafe_one(
    tmp_path, capsys, monkeypatch, runout_s, queue_s, failed
):
    pytest.importorskip("qi")
    from bearchair.executive import walk_check
    from bearchair.hardware.real.standins import NaoqiStandin

    monkeypatch.setattr(walk_check, "WALK_S", 0.5)
    monkeypatch.setattr(walk_check, "REPLACE_WAIT_S", 0.3)
    monkeypatch.setattr(walk_check, "DISCONNECT_WAIT_S", 0.3)
    monkeypatch.setattr(walk_check, "MAX_RUNOUT_S", 0.8)  # heartbeat 0.45 s, a quick stop
    with NaoqiStandin(stop_runout_s=runout_s, move_queue_s=queue_s) as naoqi:
        code = main(
            [
                "check-hardware",
                "--robots",
                str(standin_cell_file(tmp_path, naoqi.url)),
                "--move",
                "--walk",
            ]
        )
        out = capsys.readouterr().out
    assert "] nao walk run-out:" in out and "] nao walk commands:" in out
    assert "] nao walk disconnect:" in out
    assert code == (1 if failed else 0), out
    if failed:
        assert f"[FAIL] nao walk {failed}" in out


def test_a_run_on_robots_stops_when_the_monitor_sees_a_fault(tmp_path, capsys):
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin(time_scale=20.0) as naoqi:
        naoqi.battery_percent = 9
        out = tmp_path / "run"
        status = main(
            [
                "run",
                "--robots",
                str(standin_cell_file(tmp_path, naoqi.url)),
                "--yes",
                "--out",
                str(out),
            ]
        )
        capsys.readouterr()
    summary = json.loads((out / "summary.json").read_text())
    assert status == 1 and summary["outcome"] == "failure"
    assert "battery is at 9 %" in summary["reason"], summary["reason"]


# --- defects put back (issue 30's closing list): the ones the tests above let through ----


@pytest.mark.parametrize("calibrated", [False, True])
def test_check_hardware_prints_the_mirroring_and_the_intrinsics_it_read_back(
    tmp_path, capsys, calibrated
):
    pytest.importorskip("qi")
    from bearchair.hardware.real.standins import NaoqiStandin

    with NaoqiStandin() as naoqi:
        raw = json.loads(_cell_text(naoqi.url))
        if calibrated:
            raw["camera_intrinsics"] = {
                "fx_px": 561.2,
                "fy_px": 560.8,
                "cx_px": 322.0,
                "cy_px": 241.5,
            }
        cell = tmp_path / "cell.json"
        cell.write_text(json.dumps(raw))
        status = main(["check-hardware", "--robots", str(cell)])
        out = capsys.readouterr().out
    assert status == 0, out
    assert "[  ok] camera mirroring: off (read back from the streams)" in out
    if calibrated:
        assert "[  ok] camera intrinsics: fx 561.2 fy 560.8 cx 322.0 cy 241.5 px (cell file)" in out
    else:
        # The stand-in's colour stream: a 525 px focal length, not the depth camera's 570.3.
        assert "[  ok] camera intrinsics: fx 525.0 fy 525.0 cx 319.5 cy 239.5 px (colour" in out


def test_the_openni_standin_starts_every_stream_mirrored_as_the_ps1080_driver_does():
    def render(width, height):
        rgb = np.zeros((height, width, 3), np.uint8)
        rgb[:, : width // 4] = 255  # a white band on the left
        depth = np.full((height, width), 2000, np.uint16)
        depth[:, : width // 4] = 1000  # nearer on the left
        return rgb, depth

    openni = OpenNI2Standin(render=render)
    device = openni.Device.open_any()
    depth, colour = device.create_depth_stream(), device.create_color_stream()
    assert depth.get_mirroring_enabled() and colour.get_mirroring_enabled()
    depth.start()
    colour.start()
    # Copied while each frame is alive: the driver reuses a released frame's buffer.
    colour_frame, depth_frame = colour.read_frame(), depth.read_frame()
    rgb = np.array(colour_frame.get_buffer_as_uint8(), np.uint8).reshape(240, 320, 3)
    mm = np.array(depth_frame.get_buffer_as_uint16(), np.uint16).reshape(240, 320)
    # Left and right swapped, as the driver sends them until told otherwise.
    assert rgb[:, -10:].min() == 255 and rgb[:, :10].max() == 0
    assert mm[:, -10:].max() == 1000 and mm[:, :10].min() == 2000


def test_the_realsense_standins_unaligned_depth_sits_beside_its_colour():
    from bearchair.hardware.real.standins import RealSenseStandin
    from bearchair.hardware.real.standins.realsense import DEPTH_TO_COLOUR_SHIFT_PX

    def render(width, height):
        rgb = np.zeros((height, width, 3), np.uint8)
        rgb[:, width // 2 :] = 255
        depth = np.full((height, width), 800, np.uint16)
        depth[:, width // 2 :] = 1200  # the depth edge is the colour edge
        return rgb, depth

    rs = RealSenseStandin(render=render)
    config = rs.config()
    config.enable_stream(rs.stream.depth, 640, 480, rs.format.z16, 30)
    config.enable_stream(rs.stream.color, 640, 480, rs.format.rgb8, 30)
    pipeline = rs.pipeline()
    pipeline.start(config)
    frames = pipeline.wait_for_frames()
    raw = np.asarray(frames.get_depth_frame().get_data())
    colour = np.asarray(frames.get_color_frame().get_data())
    colour_edge = int(np.argmax(colour[0, :, 0] > 0))
    depth_edge = int(np.argmax(raw[0] > 1000))
    # Unaligned depth is the depth imager's: off the colour edge by the imagers' offset.
    assert DEPTH_TO_COLOUR_SHIFT_PX >= 10
    assert depth_edge - colour_edge == DEPTH_TO_COLOUR_SHIFT_PX


def test_activating_the_robots_sets_up_the_arm_as_well_as_the_nao(naoqi):
    from bearchair.executive.cell_config import parse_cell_config
    from bearchair.hardware.real.robots import activate, connect_robots

    robot = connect_robots(parse_cell_config(json.loads(_cell_text(naoqi.url))))
    try:
        activate(robot)
        panda = getattr(robot.arm._robot, "_impl", robot.arm._robot)  # behind the SDK double
        assert panda.collision_thresholds is not None
        assert panda.collision_thresholds[0] == list(COLLISION_TORQUE_NM)
        assert panda.load is not None and panda.load[0] == pytest.approx(0.16)
        assert naoqi.called("wakeUp")
    finally:
        robot.close()


def test_check_hardware_checks_the_views_against_an_fr3s_own_limits(tmp_path, capsys, monkeypatch):
    pytest.importorskip("qi")
    from bearchair.hardware.real import robots
    from bearchair.hardware.real.standins import NaoqiStandin

    def fr3(host):
        panda = PandaStandin(host)
        panda.model = "fr3"
        return panda

    monkeypatch.setattr(robots, "PandaStandin", fr3)
    with NaoqiStandin() as naoqi:
        status = main(["check-hardware", "--robots", str(standin_cell_file(tmp_path, naoqi.url))])
        out = capsys.readouterr().out
    # scan8's joint 6 (0.4258 rad) is clear on the FER, 0.15 rad inside the FR3's wall.
    assert "[  ok] panda limits: from the robot: joint 6 [0.5445," in out
    assert "[FAIL] view scan8: joint 6 target 0.4258 rad" in out
    assert status == 1 and out.strip().splitlines()[-1] == "check-hardware: FAILED: view scan8"


def test_the_cameras_reads_take_the_bound_the_panda_is_connected_with(monkeypatch):
    from bearchair.core.errors import BackendUnavailable as Unavailable
    from bearchair.executive.cell_config import parse_cell_config
    from bearchair.hardware.real import robots

    monkeypatch.setattr(robots, "OpenNI2Standin", lambda: OpenNI2Standin(silent=True))
    arm = robots.connect_panda(parse_cell_config(json.loads(_cell_text("tcp://127.0.0.1:9"))), 0.3)
    started = time.monotonic()
    with pytest.raises(Unavailable, match=r"the Carmine sent no depth frame in 0\.3 s"):
        arm.capture()
    assert time.monotonic() - started < 1.5


def test_a_device_fault_stops_the_robots_before_the_tree():
    """The monitor's fault: the robots are stopped at once, then the tree (whose leaves
    may take a while to cancel), not only when the run shuts down."""
    import py_trees

    from bearchair.core.arena import DEFAULT_ARENA
    from bearchair.executive.runner import MissionRunner
    from bearchair.hardware.fakes import fake_robot
    from bearchair.hardware.real import RobotFault
    from bearchair.testing.scripted import ScriptedSkills

    order: list[str] = []

    class Moving(py_trees.behaviour.Behaviour):
        def update(self):
            return py_trees.common.Status.RUNNING

        def terminate(self, new_status):
            if new_status == py_trees.common.Status.INVALID:
                order.append("tree")

    def fault(runner):
        raise RobotFault("the NAO's battery is at 9 % (below 15 %)")

    robot = fake_robot()
    robot.emergency_stop = lambda: order.append("robots")  # type: ignore[method-assign]
    runner = MissionRunner(
        Moving("Moving"),
        ScriptedSkills(),
        robot,
        seed=1,
        arena=DEFAULT_ARENA,
        tick_period_s=0.001,
        on_tick=fault,
    )
    runner.run()
    assert order[:2] == ["robots", "tree"], order
