"""Pictures that explain: the tree's glyphs and legend, the blackboard table, the scene
pictures' captions and overlays, one renderer for imagined poses."""

from __future__ import annotations

import html
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from bearchair.executive.tree_picture import FONT, blackboard_matrix, tree_graph
from bearchair.executive.tree_render import blackboard_users, render_graph
from bearchair.trees.mission import create_tree

needs_dot = pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz's dot is absent")


def label_characters(dot_source: str) -> set[str]:
    """Every character a label of the dot source draws (HTML tags and entities undone)."""
    drawn = set()
    for label in re.findall(r"label=<(.*?)>[,\]]", dot_source, flags=re.S):
        drawn |= set(html.unescape(re.sub(r"<[^>]*>", "", label)))
    for label in re.findall(r'label="((?:[^"\\]|\\.)*)"', dot_source):
        drawn |= set(label)
    return drawn - {"\n"}


def font_file(family: str) -> str:
    """The font file fontconfig (hence Graphviz) draws ``family`` with."""
    return subprocess.run(
        ["fc-match", "--format=%{file}", family], capture_output=True, text=True, check=True
    ).stdout


@needs_dot
@pytest.mark.parametrize("with_blackboard", [False, True])
def test_the_tree_picture_has_a_glyph_for_every_character_it_draws(tmp_path, with_blackboard):
    ttlib = pytest.importorskip("fontTools.ttLib")
    if shutil.which("fc-match") is None:
        pytest.skip("fontconfig's fc-match is absent")
    source = tree_graph(create_tree(), with_blackboard).to_string()
    assert f'fontname="{FONT}"' in source
    drawn = label_characters(source)
    assert {"S", "q", "(", ":"} <= drawn  # the labels were found
    cmap = ttlib.TTFont(font_file(FONT)).getBestCmap()
    missing = sorted(c for c in drawn if c != " " and ord(c) not in cmap)
    assert missing == [], f"no glyph in {font_file(FONT)} for {missing}"
    # py_trees' own picture asks for U+24C2 (memory), which the font lacks: the check bites.
    assert 0x24C2 not in cmap or "Ⓜ" not in drawn
    out = render_graph(create_tree(), "png", tmp_path / "tree.png", with_blackboard)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_tree_picture_has_a_legend_and_names_the_memory_mark():
    graph = tree_graph(create_tree())
    source = graph.to_string()
    assert "cluster_legend" in source
    for kind in ("Sequence", "Selector", "Decorator", "Leaf"):
        assert kind in source
    # The root is a sequence with memory, a leaf has none: their labels say so in words.
    labels = {
        str(node.get("label")).split("<BR/>")[0]: str(node.get("label"))
        for node in graph.get_nodes()
    }
    assert "<I>memory</I>" in labels["<Put the bear on the chair"]
    assert "memory" not in labels["<ScanChair>"]


def test_the_blackboard_table_holds_every_registration_and_no_other():
    root = create_tree()
    keys, users, access = blackboard_matrix(root)
    expected: dict[tuple[str, str], set[str]] = {}
    for key, registrations in blackboard_users(root).items():
        for name, mode in registrations:
            expected.setdefault((key, name), set()).add(mode)
    from_tree = {cell: "".join(sorted(modes)) for cell, modes in expected.items()}
    assert {c: m for c, m in access.items() if c[1] != "executive"} == from_tree
    assert access[("/mission/seed", "executive")] == "W"
    assert set(keys) == {k for k, _ in access} and users[0] == "executive"
    label = tree_graph(root, with_blackboard=True).get_node("blackboard")[0].get("label")
    assert label.count("<TR>") == len(keys) + 2  # title, header, a row per key


# --- scene pictures ---------------------------------------------------------------------


def white_rows(rgb) -> int:
    """Rows that are (almost) all background white: the band the far plane left."""
    import numpy as np

    return int(((np.asarray(rgb)[:, :, :3].min(axis=2) >= 250).mean(axis=1) > 0.98).sum())


@pytest.fixture(scope="module")
def world():
    from bearchair.hardware.sim.world import SimConfig, SimWorld

    with SimWorld(SimConfig(seed=0, camera_noise=False)) as built:
        yield built


def board_with_decisions():
    """A blackboard holding a path, a goal and a sitting pose, as the mission writes them."""
    import numpy as np

    from bearchair.behaviours import keys
    from bearchair.core.geometry import SittingPose
    from bearchair.core.se2 import SE2Pose
    from bearchair.skills.results import AccessibilityResult

    goal = SE2Pose(1.15, -0.1, 3.0)
    pose = SittingPose(np.array([0.8, -0.07, 0.28]), -0.12)
    path = (SE2Pose(1.9, 0.0, 3.14), SE2Pose(1.5, -0.05, 3.1))
    return {
        keys.ACCESSIBILITY: AccessibilityResult(True, goal, pose, path),
        keys.SE2_GOAL: goal,
        keys.SITTING_POSE: pose,
    }


@pytest.mark.parametrize("view", ["perspective", "top"])
def test_a_scene_picture_has_no_blank_band_and_carries_its_caption_and_marks(world, view):
    import numpy as np

    from bearchair.executive import scene_picture
    from bearchair.executive.scene_picture import SceneCaption, SceneMarks

    frame = world.render_scene(view)
    assert white_rows(frame.rgb) == 0
    marks = SceneMarks.from_blackboard(board_with_decisions())
    assert marks.path_xy.shape == (3, 2) and marks.goal is not None and marks.sitting is not None
    caption = SceneCaption("box-chair", 7, "WalkToChair", "FAILURE", 31.25, "path blocked")
    picture, lines = scene_picture.compose(frame, marks, caption)
    assert lines[0] == "box-chair | seed 7 | WalkToChair: FAILURE | robot time 31.2 s"
    assert lines[1] == "why: path blocked" and lines[-1] == scene_picture.LEGEND
    assert picture.width == frame.rgb.shape[1] and picture.height > frame.rgb.shape[0]
    pixels = np.asarray(picture)
    scene, band = pixels[: frame.rgb.shape[0]], pixels[frame.rgb.shape[0] :]
    assert (band == scene_picture.CAPTION_BACKGROUND).all(axis=2).mean() > 0.8  # a dark band
    assert (band.max(axis=2) > 200).any()  # with text in it
    assert white_rows(pixels) == 0
    # The marks are drawn where the camera sees them: the goal's base in its colour.
    ((u, v),), _ = frame.project(np.array([[1.15, -0.1, 0.01]]))
    patch = scene[int(v) - 3 : int(v) + 4, int(u) - 3 : int(u) + 4].reshape(-1, 3)
    assert (patch == scene_picture.GOAL_COLOUR).all(axis=1).any()
    assert not (frame.rgb.reshape(-1, 3) == scene_picture.GOAL_COLOUR).all(axis=1).any()


def test_stage_snapshots_of_an_unchanged_scene_differ_by_their_captions(world, tmp_path):
    from types import SimpleNamespace

    from bearchair.executive.tick_watchers import ScenePictures, StageSnapshots

    Stage = SimpleNamespace
    snapshots = StageSnapshots(ScenePictures(world, "box-chair", 0), tmp_path)
    runner = SimpleNamespace(stages=[Stage(name="ScanChair", status="SUCCESS", feedback="")])
    snapshots(runner)
    runner.stages.append(Stage(name="ImagineSitting", status="FAILURE", feedback="no sitting"))
    snapshots(runner)  # nothing moved in the world between the two stages
    contents = [p.read_bytes() for p in snapshots.written]
    assert len(contents) == 4 and len(set(contents)) == 4


# --- one renderer of imagined poses ------------------------------------------------------


def test_imagine_image_and_the_report_draw_with_the_same_renderer(tmp_path, monkeypatch):
    import math
    import types

    import numpy as np

    from bearchair.core.meshes import box_chair_mesh
    from bearchair.evaluation.pictures import render_chair_pictures
    from bearchair.evaluation.trial_record import TrialRecord
    from bearchair.executive import cmd_imagine
    from bearchair.skills.imagination import sitting_picture

    calls = []

    def recording(mesh, sitting_pose, path, title=""):
        calls.append((len(mesh.faces), sitting_pose, Path(path).name))
        Path(path).write_bytes(b"png")
        return Path(path)

    monkeypatch.setattr(sitting_picture, "render_sitting", recording)
    mesh = box_chair_mesh()
    pose = types.SimpleNamespace(position=np.array([0.0, 0.0, 0.3]), yaw=math.radians(30.0))
    result = types.SimpleNamespace(found=True, sitting_pose=pose, n_correct=3, n_drops=24)
    cmd_imagine._draw(mesh, result, "box.obj", tmp_path / "imagine.png")
    run = tmp_path / "run"
    run.mkdir()
    mesh.export(run / "chair_reconstructed.ply")
    record = TrialRecord.from_row({
        "chair": "box.obj", "placement": "accessible", "helper": "obeys", "trial_index": 0,
        "seed": 0, "experiment": "accessible", "outcome": "success", "run_dir": str(run),
        "sitting_pose": {"position_m": [0.0, 0.0, 0.3], "yaw_deg": 30.0},
    })  # fmt: skip
    assert set(render_chair_pictures([record], tmp_path / "chairs")) == {"box.obj"}
    assert [name for _, _, name in calls] == ["imagine.png", "box.png"]
    assert calls[0][0] == calls[1][0] == len(mesh.faces)
    assert math.isclose(calls[1][1].yaw, math.radians(30.0))


@pytest.mark.slow
def test_the_imagined_pose_picture_is_two_metric_views(tmp_path):
    pytest.importorskip("matplotlib")
    import math

    import numpy as np
    from PIL import Image

    from bearchair.core.geometry import SittingPose
    from bearchair.core.meshes import box_chair_mesh
    from bearchair.skills.imagination.sitting_picture import render_sitting

    pose = SittingPose(np.array([0.02, 0.0, 0.30]), math.radians(20.0))
    path = render_sitting(box_chair_mesh(), pose, tmp_path / "pose.png", "box chair")
    width, height = Image.open(path).size
    assert width > 1.8 * height  # side by side: from above, from the side
    alone = render_sitting(box_chair_mesh(), None, tmp_path / "alone.png", "box chair")
    assert alone.read_bytes() != path.read_bytes()


def test_a_caption_says_why_a_stage_failed_and_what_a_successful_one_reported():
    from bearchair.executive.scene_picture import SceneCaption

    done = SceneCaption("c.obj", 1, "ScanChair", "SUCCESS", 2.0, "chair from 9 views")
    failed = SceneCaption("c.obj", 1, "final", "FAILURE at WalkToChair", 2.0, "blocked")
    assert done.lines()[1] == "chair from 9 views" and not done.failed
    assert failed.lines()[1] == "why: blocked" and failed.failed
    assert len(SceneCaption("c.obj", 1, "final", "SUCCESS", 2.0).lines()) == 2
