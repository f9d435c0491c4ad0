"""Rerun recordings of a mission: a short mission on the box chair is recorded and read
back (entity paths, the tree's statuses at given ticks, the sitting pose's values).

The scan and the imagination are the real skills on a synthetic scan of the box chair
(so the recording holds real depth views and real drops); the later stages are
scripted, with one rotation asked of the helper. Skipped without rerun-sdk (the
``[viewer]`` extra).
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

from bearchair.behaviours import keys
from bearchair.core.arena import DEFAULT_ARENA
from bearchair.core.geometry import SittingPose, yaw_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.se2 import SE2Pose
from bearchair.executive import cli
from bearchair.executive.cmd_config import mission_from_args
from bearchair.executive.records.run_record import RunRecorder, load_ticks
from bearchair.executive.records.run_summary import RunInfo, RunSummary
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.hardware.fakes import FakeJudge, fake_robot
from bearchair.hardware.interfaces import SeatingJudgement
from bearchair.skills.results import AccessibilityResult
from bearchair.testing.scripted import ScriptedSkills, default_results
from bearchair.trees.mission import create_tree

pytest.importorskip("rerun", reason="rerun-sdk (the [viewer] extra) is not installed")

from bearchair.executive.recording.mission_recording import (
    RECORDING_FILE,
    STATUS_COLOURS,
    MissionRecording,
)
from bearchair.executive.recording.read_back import read_entity
from bearchair.executive.skill_calls import SkillCalls

T_WORLD_CHAIR = yaw_transform(0.6, np.array([0.58, 0.08, 0.0]))
BEAR_AT = yaw_transform(0.3, np.array([0.6, 0.05, 0.3]))


@pytest.fixture(scope="module")
def box_chair_results():
    """The real scan (9 synthetic views) and imagination (24 drops) of the box chair."""
    from bearchair.skills.imagination import imagine_sitting
    from bearchair.skills.perception import scan_chair
    from bearchair.testing.synthetic_scenes import SyntheticArm, SyntheticScene

    scene = SyntheticScene(seed=3)
    scene.add_mesh(box_chair_mesh(), T_WORLD_CHAIR)
    arm = SyntheticArm(scene)
    try:
        scan = scan_chair(arm, seed=0)
    finally:
        arm.close()
        scene.close()
    imagination = imagine_sitting(scan.chair_mesh, seed=0, workers=1)
    assert imagination.found, imagination.reason
    return scan, imagination


@pytest.fixture(scope="module")
def recorded(box_chair_results, tmp_path_factory):
    """One recorded mission: its run folder, summary and the skills it used."""
    import py_trees

    py_trees.blackboard.Blackboard.clear()
    scan, imagination = box_chair_results
    accessible = default_results()["check_accessibility"]
    moved_pose = SittingPose(imagination.sitting_pose.position + np.array([0.01, 0.0, 0.0]), 0.1)
    blocked = AccessibilityResult(False, None, imagination.sitting_pose, (), "s_goal outside")
    skills = ScriptedSkills(
        {
            "scan_chair": scan,
            "imagine_sitting": imagination,
            "check_accessibility": [blocked, accessible._replace(sitting_pose=moved_pose)],
            "locate_humanoid": [SE2Pose(1.9, 0.0, math.pi), None, SE2Pose(1.2, 0.05, math.pi)],
        },
        # Each stage lasts a few ticks, as real skills do (instant ones finish in one).
        delays_s={name: 0.02 for name in default_results() if name != "locate_humanoid"},
    )
    judge = FakeJudge()
    judge.judgement = SeatingJudgement(True, True, 5.0, 3.0, "", BEAR_AT)
    robot = fake_robot(judge=judge)
    out_dir = tmp_path_factory.mktemp("recorded")
    root = create_tree()
    recorder = RunRecorder(out_dir, root)
    recording = MissionRecording(root, path=out_dir / RECORDING_FILE)
    runner = MissionRunner(
        root,
        recording.watch_skills(skills, robot.clock),
        robot,
        seed=3,
        arena=DEFAULT_ARENA,
        recorder=recorder,
        tick_period_s=0.002,
        timeout_s=60,
        post_tick=(recording,),
    )
    summary = summarise(runner.run(), RunInfo(chair="box"))
    recording.log_summary(summary)
    recorder.write_summary(summary)
    recorder.close()
    recording.close()
    py_trees.blackboard.Blackboard.clear()
    return out_dir, summary, skills, recording, moved_pose


def test_the_recorded_mission_succeeded_with_one_rotation(recorded):
    out_dir, summary, _, recording, _ = recorded
    assert summary.outcome == "success", summary.reason
    assert summary.rotations == 1
    assert (out_dir / RECORDING_FILE).stat().st_size > 100_000  # depth views, mesh, drops
    assert recording.seconds > 0.0


def test_the_recording_has_every_domain_s_entities(recorded):
    paths = _entity_paths(recorded[0] / RECORDING_FILE)
    expected = {
        "/tree",
        "/tree/log",
        "/world",
        "/world/arena/walls",
        "/world/arena/obstacles",
        "/world/scan/cloud",
        "/world/chair",
        "/world/sitting_pose",
        "/world/accessibility/se2_goal",
        "/world/accessibility/path",
        "/world/nao",
        "/world/panda/visual_geometries/panda_link3/visual_0",
        "/world/NaoH25V50/visual_geometries/LThigh/LThigh_visual_0",
        "/transforms/panda/joints",
        "/transforms/panda/root",
        "/transforms/nao/joints",
        "/transforms/nao/root",
        "/world/walk/tag_detections",
        "/world/walk/path",
        "/walk/tag_seen",
        "/walk/log",
        "/world/bear",
        "/imagination/verdicts",
        "/assistance/asked_deg",
        "/assistance/measured_deg",
        "/seat/judgement",
        "/seat/plan/LHipPitch",
        "/mission/summary",
        "/blackboard/chair/scan",
        "/blackboard/sitting/pose",
        "/blackboard/seat/judgement",
        "/blackboard/accessibility/reachable",
        "/accessibility/log",
    }
    assert expected <= paths, sorted(expected - paths)
    for view in range(9):
        for child in ("", "/depth", "/rgb"):
            assert f"/world/scan/views/{view}{child}" in paths
    for drop in range(24):
        assert f"/world/imagination/drops/{drop}" in paths


def test_tree_statuses_at_given_ticks_match_the_run_record(recorded):
    out_dir = recorded[0]
    rows = [row for row in read_entity(out_dir / RECORDING_FILE, "tree") if "status" in row]
    assert rows, "no tree statuses recorded"
    tree = json.loads((out_dir / "tree.json").read_text())
    names = [node["name"] for node in tree]
    by_tick = {row["tick"]: row for row in rows}
    # Every tick the run record wrote, the recording agrees node by node.
    checked = 0
    for tick in load_ticks(out_dir):
        if tick["tick"] not in by_tick:
            continue  # the final record of a run repeats the last tick
        row = by_tick[tick["tick"]]
        assert row["status"] == [node["status"] for node in tick["nodes"]]
        assert row["GraphNodes:node_ids"] == [node["path"] for node in tick["nodes"]]
        checked += 1
    assert checked >= 10
    robot_s = [row["robot"] for row in rows]  # the robot's clock, in seconds
    assert all(isinstance(t, float) for t in robot_s) and robot_s == sorted(robot_s)
    first, last = rows[0], rows[-1]
    assert first["status"][names.index("ScanChair")] == "RUNNING"
    assert first["status"][names.index("WalkToChair")] == "INVALID"
    assert all(status == "SUCCESS" for status in last["status"][:2])
    assert last["status"][names.index("ReleaseAndStand")] == "SUCCESS"
    # The tick the first accessibility check failed, the helper was asked next.
    check = names.index("CheckAccessibility")
    failed_at = next(row["tick"] for row in rows if row["status"][check] == "FAILURE")
    assert by_tick[failed_at]["status"][names.index("WalkToChair")] == "INVALID"
    later = [row for row in rows if row["tick"] > failed_at]
    assert later[0]["status"][names.index("InstructHelper")] in ("RUNNING", "SUCCESS")
    assert any(row["status"][names.index("CheckAccessibilityAgain")] == "SUCCESS" for row in later)
    # Colours follow the statuses; feedback sits in the labels.
    colours = [tuple(int(c) for c in _rgb(value)) for value in last["GraphNodes:colors"]]
    assert colours == [STATUS_COLOURS[status] for status in last["status"]]
    scan_label = last["GraphNodes:labels"][names.index("ScanChair")]
    assert scan_label.startswith("ScanChair\nchair reconstructed from 9 views")


def test_sitting_pose_values_are_recorded_as_imagined_then_as_moved(recorded, box_chair_results):
    out_dir, _, _, _, moved_pose = recorded
    imagined = box_chair_results[1].sitting_pose
    rows = read_entity(out_dir / RECORDING_FILE, "world/sitting_pose")
    arrows = [row for row in rows if row.get("Arrows3D:origins")]
    assert len(arrows) >= 2
    ticks = [row["tick"] for row in arrows]
    assert ticks == sorted(ticks)
    for row, pose in ((arrows[0], imagined), (arrows[-1], moved_pose)):
        (origin,) = row["Arrows3D:origins"]
        (vector,) = row["Arrows3D:vectors"]
        assert np.allclose(origin, pose.position, atol=1e-6)
        assert math.isclose(math.atan2(vector[1], vector[0]), pose.yaw, abs_tol=1e-6)
        assert row["yaw_rad"] == [pytest.approx(pose.yaw)]


def test_drops_are_drawn_where_the_imagination_left_them(recorded, box_chair_results):
    out_dir = recorded[0]
    imagination = box_chair_results[1]
    for index in (0, 11, 23):
        drop = imagination.drops[index]
        (row,) = [
            r
            for r in read_entity(out_dir / RECORDING_FILE, f"world/imagination/drops/{index}")
            if r.get("Boxes3D:centers")
        ]
        pelvis = (imagination.T_mesh_chair @ np.append(drop.position, 1.0))[:3]
        assert np.allclose(row["Boxes3D:centers"][0], pelvis, atol=1e-5)  # the pelvis box
        assert len(row["Boxes3D:centers"]) == len(drop.link_poses)
        assert row["correct"] == [drop.correct]


def test_scan_views_carry_depth_in_millimetres_and_the_camera_pose(recorded, box_chair_results):
    out_dir = recorded[0]
    frame = box_chair_results[0].frames[4]
    (pose,) = [
        r
        for r in read_entity(out_dir / RECORDING_FILE, "world/scan/views/4")
        if r.get("Transform3D:translation")
    ]
    assert np.allclose(pose["Transform3D:translation"], frame.T_world_camera[:3, 3], atol=1e-6)
    (depth,) = read_entity(out_dir / RECORDING_FILE, "world/scan/views/4/depth")
    assert depth["EncodedDepthImage:meter"] == [1000.0]
    png = np.frombuffer(bytes(depth["EncodedDepthImage:blob"][0]), dtype=np.uint8)
    depth_mm = cv2.imdecode(png, cv2.IMREAD_UNCHANGED)
    assert depth_mm.dtype == np.uint16 and depth_mm.shape == frame.depth_m.shape
    assert np.abs(depth_mm / 1000.0 - frame.depth_m).max() <= 0.001  # millimetres


def test_asked_and_measured_rotations_and_tag_detections(recorded):
    out_dir, _, skills, _, _ = recorded
    path = out_dir / RECORDING_FILE
    (asked,) = read_entity(path, "assistance/asked_deg")
    (measured,) = read_entity(path, "assistance/measured_deg")
    instruction = default_results()["compose_instruction"]
    assert asked["Scalars:scalars"] == [-instruction.angle_deg]  # clockwise is negative
    assert measured["Scalars:scalars"] == [pytest.approx(-90.0)]
    seen = [row["Scalars:scalars"][0] for row in read_entity(path, "walk/tag_seen")]
    assert len(seen) == len(skills.calls["locate_humanoid"])
    assert 0.0 in seen and 1.0 in seen


def test_blackboard_text_is_logged_when_a_value_changes(recorded):
    out_dir = recorded[0]
    rows = read_entity(out_dir / RECORDING_FILE, "blackboard/assistance/rotations")
    assert [json.loads(row["TextDocument:text"][0]) for row in rows] == [1]
    judgement = read_entity(out_dir / RECORDING_FILE, "blackboard/seat/judgement")
    assert json.loads(judgement[-1]["TextDocument:text"][0])["seated"] is True


def test_the_seating_plan_is_on_its_own_timeline(recorded):
    rows = read_entity(recorded[0] / RECORDING_FILE, "seat/plan/LHipPitch")
    plan = default_results()["plan_seating"]
    assert len(rows) == len(plan.times_s) + len(plan.retract_times_s)
    assert all("tick" not in row and "seat_plan" in row for row in rows)


def test_skill_calls_pass_through_and_are_queued():
    class Clock:
        def now(self) -> float:
            return 4.5

    skills = ScriptedSkills()
    calls = SkillCalls(skills, Clock())
    pose = calls.locate_humanoid("arm")
    assert pose == default_results()["locate_humanoid"]
    calls.walk_path(None, None, None, ())  # passed through, not watched
    assert calls.drain() == [("locate_humanoid", pose, 4.5)]
    assert calls.drain() == []
    assert len(skills.calls["walk_path"]) == 1


def test_a_failing_logger_never_stops_the_mission(tmp_path, caplog):
    root = create_tree()
    recording = MissionRecording(root, path=tmp_path / RECORDING_FILE)
    broken_arena = object()  # not an Arena: its logger raises
    runner = MissionRunner(
        root,
        ScriptedSkills(),
        fake_robot(judge=FakeJudge()),
        seed=1,
        arena=broken_arena,
        tick_period_s=0.002,
        timeout_s=30,
        post_tick=(recording,),
    )
    outcome = runner.run()
    recording.close()
    assert outcome.status.value == "SUCCESS"
    assert any(keys.ARENA in message for message in caplog.messages)


def test_live_web_serves_the_viewer_while_recording_to_a_file(tmp_path):
    import socket
    import urllib.request

    def free_port() -> int:
        with socket.socket() as probe:
            probe.bind(("127.0.0.1", 0))
            return probe.getsockname()[1]

    web_port, grpc_port = free_port(), free_port()
    root = create_tree()
    recording = MissionRecording(
        root, path=tmp_path / RECORDING_FILE, live="web", web_port=web_port, grpc_port=grpc_port
    )
    try:
        assert recording.viewer_url.startswith(f"http://127.0.0.1:{web_port}/?url=")
        assert f"%3A{grpc_port}%2Fproxy" in recording.viewer_url
        with urllib.request.urlopen(f"http://127.0.0.1:{web_port}/", timeout=10) as page:
            assert page.status == 200
    finally:
        recording.close()
    assert {"/tree", "/world"} <= _entity_paths(tmp_path / RECORDING_FILE)


def test_run_record_and_live_flags(tmp_path, monkeypatch, capsys):
    args = cli.build_parser().parse_args(["run", "--record", "--live", "web"])
    assert args.record is True and args.live == "web"
    plain = cli.build_parser().parse_args(["run"])
    assert plain.record is None  # left to the configuration, whose default is off
    assert mission_from_args(plain).outputs.record is False
    assert cli.build_parser().parse_args(["run", "--live"]).live == "spawn"
    trials = cli.build_parser().parse_args(["trials", "--chairs", "x", "--no-record"])
    assert trials.record is False
    assert cli.build_parser().parse_args(["trials", "--chairs", "x"]).record is True
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    assert cli.main(["run", "--live", "--out", str(tmp_path / "x")]) == 2
    assert "use --live web" in capsys.readouterr().err
    assert cli.main(["run", "--live", "ftp://x", "--out", str(tmp_path / "y")]) == 2
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_trials_pass_record_to_each_worker(tmp_path, monkeypatch, capsys):
    import bearchair.executive.run
    from bearchair.evaluation import worker
    from bearchair.evaluation.campaign import run_campaign
    from bearchair.evaluation.protocol import ChairEntry, expand_protocol
    from bearchair.evaluation.store import TrialStore

    class Backend:
        def run(self, jobs, record):
            self.payloads = [payload for _, payload in jobs]

    specs = expand_protocol([ChairEntry(tmp_path / "c.obj", "chair", 90.0)], "paper", 1)
    for record in (True, False):
        backend = Backend()
        with TrialStore(tmp_path / f"{record}.sqlite") as store:
            run_campaign(specs, store, backend, tmp_path / "runs", 60, record=record)
        assert [payload["record"] for payload in backend.payloads] == [record] * len(specs)
    # The worker turns it into the run's configuration.
    configs = []
    monkeypatch.setattr(
        bearchair.executive.run,
        "run_in_simulation",
        lambda config, **_: configs.append(config) or RunSummary(outcome="success"),
    )
    for record in (True, False):
        payload = {**backend.payloads[0], "record": record, "out_dir": str(tmp_path / "w")}
        assert worker.main([json.dumps(payload)]) == 0
    assert [config.record for config in configs] == [True, False]
    capsys.readouterr()


def test_view_explains_a_missing_recording_and_builds_the_viewer_command(tmp_path, capsys):
    from bearchair.executive.cmd_view import viewer_command

    assert cli.main(["view", str(tmp_path)]) == 2
    assert "bearchair run --record" in capsys.readouterr().err
    assert cli.main(["view", str(tmp_path / "nothing")]) == 2
    (tmp_path / RECORDING_FILE).write_bytes(b"")
    command = viewer_command(tmp_path / RECORDING_FILE, web=True, port=9123)
    assert command[0].endswith("rerun") and "--web-viewer" in command
    assert command[command.index("--web-viewer-port") + 1] == "9123"
    assert command[-1] == str(tmp_path / RECORDING_FILE)


def test_view_web_serves_a_recording(recorded):
    import socket
    import subprocess
    import sys
    import time
    import urllib.request

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    viewer = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bearchair.executive.cli",
            "view",
            str(recorded[0]),
            "--web",
            "--port",
            str(port),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 30.0
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2) as page:
                    assert page.status == 200
                    break
            except OSError:
                assert viewer.poll() is None, viewer.stderr.read().decode()
                assert time.monotonic() < deadline, "the web viewer did not answer in 30 s"
                time.sleep(0.3)
    finally:
        viewer.terminate()
        viewer.wait(timeout=10)


def _entity_paths(path) -> set[str]:
    from rerun.chunk import RrdReader

    return set(RrdReader(str(path)).store().schema().entity_paths())


def _rgb(packed: int) -> tuple[int, int, int]:
    """Rerun stores colours as 0xRRGGBBAA."""
    return ((packed >> 24) & 0xFF, (packed >> 16) & 0xFF, (packed >> 8) & 0xFF)


def test_the_recording_opens_with_the_mission_layout(recorded):
    from bearchair.executive.recording.layout import CAMERA_VIEW_TABS, blueprint_views

    views = blueprint_views(recorded[0] / RECORDING_FILE)
    assert ("3D", "scene", "world") in views
    assert ("Graph", "tree", "tree") in views
    assert ("TimeSeries", "rotations (deg)", "assistance") in views
    assert ("TimeSeries", "seating plan (rad)", "seat/plan") in views
    assert ("TextLog", "log", "/") in views
    cameras = {origin for kind, _, origin in views if kind == "2D"}
    assert cameras == {f"world/scan/views/{i}" for i in range(CAMERA_VIEW_TABS)}
    # Every view's origin holds data in the recording (no empty panel by a typo).
    recorded_paths = _entity_paths(recorded[0] / RECORDING_FILE)
    for kind, name, origin in views:
        if origin != "/":
            assert any(p == f"/{origin}" or p.startswith(f"/{origin}/") for p in recorded_paths), (
                f"{kind} view {name!r}: nothing recorded under {origin}"
            )


def _joint_states(path, robot: str, child_frame: str) -> list[dict]:
    """Each logged state of one joint: robot time, translation and quaternion (xyzw)."""
    states = []
    for row in read_entity(path, f"transforms/{robot}/joints"):
        children = row["Transform3D:child_frame"]
        if child_frame in children:
            index = children.index(child_frame)
            states.append(
                {
                    "robot": row["robot"],
                    "translation": row["Transform3D:translation"][index],
                    "quaternion": row["Transform3D:quaternion"][index],
                }
            )
    return states


def test_the_robots_move_with_their_joint_states(recorded):
    out_dir, _, skills, _, _ = recorded
    path = out_dir / RECORDING_FILE
    # The Panda's root hangs from the arm's base, the NAO's from its tracked pose.
    (panda_root,) = read_entity(path, "transforms/panda/root")
    assert panda_root["Transform3D:parent_frame"] == ["tf#/world/arm_base"]
    assert panda_root["Transform3D:child_frame"] == ["panda/panda_link0"]
    nao_roots = read_entity(path, "transforms/nao/root")
    assert {tuple(row["Transform3D:parent_frame"]) for row in nao_roots} == {("tf#/world/nao",)}
    # The arm's seven joints were logged as they changed (the fake arm stays still:
    # once), each from its parent link's frame to its child's.
    (arm,) = read_entity(path, "transforms/panda/joints")
    assert arm["Transform3D:child_frame"] == [f"panda/panda_link{i}" for i in range(1, 8)]
    assert arm["Transform3D:parent_frame"] == [f"panda/panda_link{i}" for i in range(7)]
    # The NAO's hips as the seating plan and the retract motion played them.
    plan = skills.calls["execute_seating"][0][0][1]
    states = _joint_states(path, "nao", "nao/LThigh")
    moved = states[1:]  # the first: the carrying posture before the first tick
    assert len(moved) == len(plan.times_s) + len(plan.retract_times_s)
    seating, retract = moved[: len(plan.times_s)], moved[len(plan.times_s) :]
    # Each knot at the robot time it was played: the motion's start plus the knot's time
    # (the scripted skills take no robot time, so both motions start at the same time).
    started = seating[0]["robot"] - plan.times_s[0]
    assert [state["robot"] - started for state in seating] == pytest.approx(list(plan.times_s))
    assert [state["robot"] - started for state in retract] == pytest.approx(
        list(plan.retract_times_s)
    )


def test_a_played_motion_poses_the_nao_knot_by_knot(tmp_path):
    import rerun as rr
    from scipy.spatial.transform import Rotation

    from bearchair.executive.recording.urdf_robots import MissionRobots

    robots = MissionRobots()
    stream = rr.RecordingStream("test")
    stream.save(str(tmp_path / "motion.rrd"))
    knees = [0.0, 0.6, 1.2]
    robots.log_nao_motion(
        stream, ("LKneePitch", "RKneePitch"), np.array([0.0, 0.5, 1.0]),
        np.array([[k, k] for k in knees]), started_s=5.0,
    )  # fmt: skip
    joint = robots.nao.joints["LKneePitch"]
    for index, knee in enumerate(knees):  # Rerun's own joint transforms, to compare
        stream.log(f"rerun/{index}", joint.compute_transform(knee))
    stream.flush()
    stream.disconnect()
    path = tmp_path / "motion.rrd"
    states = _joint_states(path, "nao", "nao/LTibia")
    assert [state["robot"] for state in states] == pytest.approx([5.0, 5.5, 6.0])
    for index, state in enumerate(states):
        (theirs,) = read_entity(path, f"rerun/{index}")
        assert state["translation"] == pytest.approx(theirs["Transform3D:translation"][0])
        ours = Rotation.from_quat(state["quaternion"])
        assert (
            Rotation.from_quat(theirs["Transform3D:quaternion"][0]).inv() * ours
        ).magnitude() < 1e-6
    # Bending the knees lowers the body: the base sinks towards the floor.
    heights = [
        row["Transform3D:translation"][0][2] for row in read_entity(path, "transforms/nao/root")
    ]
    assert heights[0] > heights[1] > heights[2] > 0.1


def test_forward_kinematics_matches_pybullet():
    import pybullet

    from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD
    from bearchair.executive.recording.urdf_robots import MissionRobots
    from bearchair.hardware.sim.bullet import (
        LockedBullet,
        T_world_link,
        joint_index_by_name,
        link_index_by_name,
        reset_base_link,
    )

    robots = MissionRobots()
    bullet = LockedBullet()
    try:
        body = bullet.loadURDF(str(robots.nao_urdf), flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        reset_base_link(bullet, body, np.eye(4))
        joints = {**CARRYING_POSTURE_RAD, "LKneePitch": 1.1, "LHipPitch": -0.6, "LAnklePitch": -0.4}
        index = joint_index_by_name(bullet, body)
        for name, value in joints.items():
            bullet.resetJointState(body, index[name], value)
        sole = T_world_link(bullet, body, link_index_by_name(bullet, body)["l_sole"])
    finally:
        bullet.disconnect_once()
    ours = robots.nao.chain(robots.nao.root_link, "l_sole", joints)
    np.testing.assert_allclose(ours, sole, atol=1e-6)
    # Laid flat: with the legs bent, the left sole is still on the floor, flat.
    T_feet_sole = robots.T_nao_base(joints) @ ours
    np.testing.assert_allclose(T_feet_sole[:3, :3], np.eye(3), atol=1e-9)
    np.testing.assert_allclose(T_feet_sole[:3, 3], [0.0, 0.05, 0.0], atol=1e-9)


def test_the_arm_is_sampled_off_the_tick_thread_when_it_moves():
    import threading
    import time

    from bearchair.executive.recording.urdf_robots import JointSampler

    angles = [np.zeros(7)]
    readers: set[str] = set()

    def read():
        readers.add(threading.current_thread().name)
        return angles[0]

    class Clock:
        def now(self):
            return 7.0

    sampler = JointSampler(read, Clock(), period_s=0.01, step_rad=0.01)
    try:
        time.sleep(0.1)
        assert [(t, list(q)) for t, q in sampler.drain()] == [(7.0, [0.0] * 7)]  # once: still
        angles[0] = np.full(7, 0.005)  # below the step: not kept
        time.sleep(0.1)
        angles[0] = np.full(7, 0.5)
        time.sleep(0.1)
        kept = sampler.drain()
        assert len(kept) == 1 and kept[0][1][0] == 0.5
    finally:
        sampler.stop()
    assert readers == {"recording-joints"}
