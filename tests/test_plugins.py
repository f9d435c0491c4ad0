"""Plug-ins: trees by SPEC, skill sets and robot backends by entry point, each checked
against its Protocol and refused in one line naming what is missing."""

from __future__ import annotations

import importlib.metadata
import threading

import py_trees
import pytest

from bearchair.core import plugins
from bearchair.core.errors import InputError, PluginError
from bearchair.core.protocols import protocol_gaps
from bearchair.executive import cli
from bearchair.executive.cell_config import CellConfigError, parse_cell_config
from bearchair.executive.tree_source import build_tree, load_tree_factory
from bearchair.hardware.backends import build_device
from bearchair.hardware.interfaces import Speaker
from bearchair.skills.mission_skills import MissionSkills
from bearchair.skills.skill_sets import apply_skill_plugins, check_skill_plugins
from bearchair.testing.scripted import ScriptedSkills
from bearchair.trees.mission import create_tree
from bearchair.trees.options import TreeOptions
from tests.helpers.cells import GOOD_CELL


def fake_entry_points(monkeypatch, group: str, **objects) -> None:
    """Entry points of ``group`` naming ``objects`` (made this module's attributes), beside
    the installed ones."""
    real = plugins.entry_points
    for name, value in objects.items():
        globals()[f"_plugin_{name.replace('-', '_')}"] = value

    def entry_points(asked: str) -> dict[str, importlib.metadata.EntryPoint]:
        found = real(asked)
        if asked == group:
            for name in objects:
                value = f"{__name__}:_plugin_{name.replace('-', '_')}"
                found[name] = importlib.metadata.EntryPoint(name, value, group)
        return found

    monkeypatch.setattr(plugins, "entry_points", entry_points)


# --- protocols ------------------------------------------------------------------------


class HalfSpeaker:
    def speak(self, sentence: str) -> None: ...


class KeywordSpeaker:
    def say(self, *, text: str) -> None: ...


class GoodSpeaker:
    def say(self, sentence: str, volume: float = 1.0) -> None: ...


def test_protocol_gaps_name_a_missing_method_and_an_unbindable_one():
    assert protocol_gaps(GoodSpeaker(), Speaker) == []
    assert protocol_gaps(HalfSpeaker(), Speaker) == ["no method say"]
    (gap,) = protocol_gaps(KeywordSpeaker(), Speaker)
    assert gap.startswith("say takes (*, text: 'str') -> 'None', not (sentence: 'str')")


@pytest.mark.slow
def test_the_default_and_the_scripted_skills_satisfy_the_protocol():
    from bearchair.skills.default_skills import DefaultSkills

    assert protocol_gaps(ScriptedSkills(), MissionSkills) == []
    assert protocol_gaps(DefaultSkills(imagination_workers=1), MissionSkills) == []


# --- trees ----------------------------------------------------------------------------


def shape(root: py_trees.behaviour.Behaviour) -> list[tuple[str, str]]:
    return [(node.name, type(node).__name__) for node in root.iterate()]


def test_a_tree_spec_is_a_name_a_module_factory_or_an_entry_point():
    assert load_tree_factory("mission") is create_tree
    assert load_tree_factory("bearchair.trees.mission:create_tree") is create_tree
    variant = load_tree_factory("example-no-assistance")  # the example plug-in's entry point
    assert "AnnounceSeat" in [name for name, _ in shape(build_tree(variant))]


@pytest.mark.parametrize(
    ("spec", "named"),
    [
        ("no-such-tree", "no tree named 'no-such-tree' (entry points bearchair.trees: example"),
        ("no_such_module:make", "--tree no_such_module:make: cannot import no_such_module"),
        ("bearchair.trees.mission:no_such", "bearchair.trees.mission has no attribute no_such"),
        ("bearchair.trees.mission:STAGES", "--tree bearchair.trees.mission:STAGES: tuple is not"),
        ("bearchair.trees.mission:create_locate_turned_chair", None),  # takes a bool: binds
        ("bearchair.trees.options:TreeOptions", None),  # callable with one argument
        ("py_trees.composites:Parallel", "a tree factory takes one argument"),
        (":create_tree", "write module:factory"),
    ],
)
def test_a_wrong_tree_spec_is_one_line(spec, named):
    if named is None:
        load_tree_factory(spec)
        return
    with pytest.raises(PluginError) as error:
        load_tree_factory(spec)
    assert named in str(error.value) and "\n" not in str(error.value)


def test_a_factory_that_returns_no_behaviour_is_refused():
    with pytest.raises(PluginError, match="returned TreeOptions, not a py_trees"):
        build_tree(load_tree_factory("bearchair.trees.options:TreeOptions"))


def test_an_xml_tree_file_that_is_missing_is_one_line(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_tree_factory(str(tmp_path / "absent.xml"))


def test_an_xml_tree_spec_builds_the_tree_the_file_describes(tmp_path):
    from bearchair.executive.btcpp import tree_to_btcpp_xml

    path = tmp_path / "mission.xml"
    path.write_text(tree_to_btcpp_xml(create_tree()))
    root = load_tree_factory(str(path))(TreeOptions())
    assert tree_to_btcpp_xml(root) == path.read_text()


def test_tree_and_run_refuse_a_bad_tree_in_one_line(tmp_path, capsys):
    assert cli.main(["tree", "--tree", "nope:nothing"]) == 2
    out = tmp_path / "run"
    assert cli.main(["run", "--tree", "no-such-tree", "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "cannot import nope" in lines[0] and "no tree named" in lines[1]
    assert not out.exists()


# --- skills ---------------------------------------------------------------------------


class NoScanSkills:
    """A skill set missing scan_chair and taking a wrong keyword in imagine_sitting."""

    def __init__(self) -> None:
        base = ScriptedSkills()
        for name in ("locate_humanoid", "check_seat_reachable", "check_accessibility"):
            setattr(self, name, getattr(base, name))

    def imagine_sitting(self, mesh, *, random_seed: int, cancel: threading.Event | None = None):
        raise NotImplementedError


def quiet_instruction(sitting_pose, humanoid_pose, rotation_rad=None):
    return (
        ScriptedSkills()
        .compose_instruction(sitting_pose, humanoid_pose)
        ._replace(sentence="(gesture)")
    )


def test_a_skill_set_that_misses_the_protocol_is_refused_naming_what_is_missing(monkeypatch):
    fake_entry_points(monkeypatch, "bearchair.skills", partial=NoScanSkills)
    with pytest.raises(PluginError) as error:
        apply_skill_plugins(ScriptedSkills(), ["partial"])
    message = str(error.value)
    assert message.startswith("skills plug-in 'partial': not a MissionSkills: no method scan_chair")
    assert "imagine_sitting takes" in message and "\n" not in message


def test_overrides_replace_single_skills_over_the_base(monkeypatch):
    fake_entry_points(
        monkeypatch, "bearchair.skills", quiet={"compose_instruction": quiet_instruction}
    )
    base = ScriptedSkills()
    skills = apply_skill_plugins(base, ["quiet"])
    pose = base.results["imagine_sitting"].sitting_pose
    assert skills.compose_instruction(pose, base.results["locate_humanoid"]).sentence == "(gesture)"
    assert skills.scan_chair is not None and skills.scan_chair.__self__ is base  # pyright: ignore[reportFunctionMemberAccess]


@pytest.mark.parametrize(
    ("overrides", "named"),
    [
        ({"compose_instrucion": quiet_instruction}, "'compose_instrucion' is not a skill"),
        ({"compose_instruction": lambda pose: None}, "the override of compose_instruction takes"),
        ({"compose_instruction": "polite"}, "the override of compose_instruction is not callable"),
        ({}, "must be a non-empty mapping"),
    ],
)
def test_a_wrong_override_is_refused_before_the_run(monkeypatch, overrides, named):
    fake_entry_points(monkeypatch, "bearchair.skills", wrong=overrides)
    with pytest.raises(PluginError, match="skills plug-in 'wrong': ") as error:
        check_skill_plugins(["wrong"])
    assert named in str(error.value)


def test_run_refuses_an_unknown_skills_plugin_in_one_line(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli.main(["run", "--set", 'skills.plugins=["nope"]', "--out", str(out)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "no skills plug-in named 'nope' (entry points bearchair.skills: example-polite" in line


# --- backends -------------------------------------------------------------------------


def test_a_backend_whose_device_misses_the_protocol_is_refused(monkeypatch):
    fake_entry_points(monkeypatch, "bearchair.backends", mumbler=lambda settings: HalfSpeaker())
    with pytest.raises(
        PluginError, match="speaker backend 'mumbler': not a Speaker: no method say"
    ):
        build_device("speaker", "mumbler", {})
    with pytest.raises(PluginError, match="no robot backend named 'nope'"):
        build_device("speaker", "nope", {})
    with pytest.raises(PluginError, match="no device role 'gripper'"):
        build_device("gripper", "mumbler", {})


def test_a_cell_section_names_a_backend_and_frees_the_built_in_fields():
    arm_only = {k: v for k, v in GOOD_CELL.items() if k not in ("panda_host", "T_flange_camera")}
    cell = parse_cell_config({**arm_only, "arm": {"backend": "my-ur5", "host": "10.0.0.2"}})
    assert cell.devices == {"arm": {"backend": "my-ur5", "host": "10.0.0.2"}}
    assert cell.panda_host is None
    assert parse_cell_config({**GOOD_CELL, "humanoid": {"backend": "nao"}}).devices == {}


@pytest.mark.parametrize(
    ("section", "named"),
    [
        ("my-ur5", 'arm: an object {"backend": NAME, ...} is needed'),
        ({"host": "x"}, "arm.backend: a backend name is needed"),
        ({"backend": "panda", "host": "x"}, "arm: the built-in panda backend takes its settings"),
    ],
)
def test_a_wrong_device_section_is_one_line(section, named):
    with pytest.raises(CellConfigError) as error:
        parse_cell_config({**GOOD_CELL, "arm": section})
    assert named in str(error.value)


def test_a_built_in_arm_still_needs_its_fields():
    without = {k: v for k, v in GOOD_CELL.items() if k != "panda_host"}
    with pytest.raises(CellConfigError, match="missing field panda_host"):
        parse_cell_config({**without, "speaker": {"backend": "example-log-speaker", "path": "x"}})


def test_the_options_reach_the_tree_through_build_tree():
    root = build_tree(create_tree, TreeOptions(max_rotations=5))
    assert [node.name for node in root.iterate() if "rotations" in node.name] == [
        "Up to 5 rotations"
    ]


# --- trials ---------------------------------------------------------------------------


def test_trials_refuse_a_bad_tree_before_any_trial(tmp_path, capsys):
    assert cli.main(["trials", "--chairs", str(tmp_path), "--tree", "no-such-tree"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "no tree named 'no-such-tree'" in line


def test_each_trial_payload_names_the_campaign_tree(tmp_path):
    from bearchair.evaluation.campaign import _jobs
    from bearchair.evaluation.protocol import ChairEntry, expand_protocol

    specs = expand_protocol([ChairEntry(tmp_path / "a.obj", "chair", 90.0)], "paper", 1)
    mission = _jobs(specs[:1], tmp_path, 60.0, False, 1)
    variant = _jobs(specs[:1], tmp_path, 60.0, False, 1, tree="example-no-assistance")
    assert "tree" not in mission[0][1]  # the shipped tree's payload is unchanged
    assert variant[0][1]["tree"] == "example-no-assistance"


def test_inspect_says_whether_the_record_is_of_the_tree_a_spec_builds(tmp_path, capsys):
    from tests.helpers.missions import run_scripted_mission

    run_scripted_mission(ScriptedSkills(), out_dir=tmp_path)
    assert cli.main(["inspect", str(tmp_path), "--tree", "mission"]) == 0
    nodes = len(list(create_tree().iterate()))
    assert f"tree: the one mission builds ({nodes} nodes)" in capsys.readouterr().out
    assert cli.main(["inspect", str(tmp_path), "--tree", "example-no-assistance"]) == 0
    assert "tree: not the one example-no-assistance builds" in capsys.readouterr().out


def test_connect_robots_makes_the_plugin_devices_and_skips_the_nao(tmp_path, monkeypatch):
    from bearchair.hardware.fakes import FakeHumanoid
    from bearchair.hardware.real.robots import activate, connect_robots

    class ActiveHumanoid(FakeHumanoid):
        activated = 0

        def activate(self) -> None:
            self.activated += 1

    fake_entry_points(monkeypatch, "bearchair.backends", toy=lambda settings: ActiveHumanoid())
    said = tmp_path / "said.txt"
    raw = {k: v for k, v in GOOD_CELL.items() if k != "nao_url"}
    cell = parse_cell_config(
        {
            **raw,
            "panda_host": "standin",  # the SDK stand-ins: no Panda needed
            "humanoid": {"backend": "toy"},
            "speaker": {"backend": "example-log-speaker", "path": str(said)},
        }
    )
    robot = connect_robots(cell)  # no nao_url: the NAO is never reached
    try:
        activate(robot)
        robot.speaker.say("Hello.")
        assert isinstance(robot.humanoid, ActiveHumanoid) and robot.humanoid.activated == 1
        assert said.read_text() == "Hello.\n"
    finally:
        robot.close()


def test_the_trial_worker_runs_the_payload_tree(tmp_path, monkeypatch, capsys):
    import json

    from bearchair.evaluation import worker
    from bearchair.executive import run as executive_run
    from bearchair.executive.records.run_summary import RunSummary
    from bearchair_example.trees import create_tree_without_assistance

    ran = {}

    def fake_run(config, on_tick=None, tree=None):
        ran.update(spec=config.tree_spec, tree=tree)
        return RunSummary(outcome="success")

    monkeypatch.setattr(executive_run, "run_in_simulation", fake_run)
    payload = {"out_dir": str(tmp_path), "placement": "accessible", "helper": "obeys"}
    payload |= {"seed": 1, "timeout_s": 60, "tree": "example-no-assistance"}
    assert worker.main([json.dumps(payload)]) == 0, capsys.readouterr().out
    assert ran == {"spec": "example-no-assistance", "tree": create_tree_without_assistance}
