"""The mission configuration: the example loads and fits the schema; a bad file is one line."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.executive import cli
from bearchair.executive.cmd_config import mission_from_args, parse_assignment
from bearchair.executive.mission_config import (
    MissionConfig,
    load_mission_config,
    parse_mission_config,
)
from bearchair.executive.run import CONFIG_FILE, write_config
from bearchair.trees.options import TreeOptions

jsonschema = pytest.importorskip("jsonschema")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "mission.toml"


def schema(capsys) -> dict:
    assert cli.main(["config", "--schema"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_example_configuration_fits_the_printed_schema_and_loads(capsys):
    jsonschema.validate(tomllib.loads(EXAMPLE.read_text()), schema(capsys))
    config = load_mission_config(EXAMPLE)
    assert config.run.mute and config.tree.options() == TreeOptions()
    assert config.arena.arena() == DEFAULT_ARENA  # the example spells out the defaults


def test_the_schema_refuses_what_the_loader_refuses(capsys):
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"tree": {"asistance": False}}, schema(capsys))


def test_an_empty_file_is_the_defaults_of_a_plain_run(tmp_path):
    (tmp_path / "empty.toml").write_text("")
    config = load_mission_config(tmp_path / "empty.toml")
    assert config == MissionConfig()
    run = config.run_config(tmp_path / "run")
    assert (run.seed, run.timeout_s, run.tree_spec, run.arena) == (
        0,
        900.0,
        "mission",
        DEFAULT_ARENA,
    )


BAD = [
    ("[tree]\nasistance = false\n", "tree.asistance: unknown key (did you mean assistance?)"),
    ("[timeouts]\nmission = 60\n", "timeouts.mission: unknown key (did you mean mission_s?)"),
    ("[arena]\nhumanoid_start_yaw_rad = 3.1\n", "did you mean humanoid_start_yaw_deg?"),
    ('[timeouts]\nmission_s = "15 min"\n', "timeouts.mission_s: Input should be a valid number"),
    ('[tree]\nassistance = "no"\n', "tree.assistance: Input should be a valid boolean"),
    (
        "[tree]\nmax_rotations = 0\n",
        "tree.max_rotations: Input should be greater than or equal to 1",
    ),
    ("[run]\nseed = -1\n", "run.seed: Input should be greater than or equal to 0"),
    ('[run]\nplacement = "nowhere"\n', "run.placement: Input should be 'accessible' or"),
    ("[scan]\nviews = [0, 1, 2]\n", "scan.views: 3 views, at least 5 needed"),
    ("[scan]\nviews = [0, 1, 2, 3, 12]\n", "scan.views: 12 is not a view index 0-8"),
    ("[scan]\nvoxel_size_m = 8\n", "scan.voxel_size_m: Input should be less than or equal to 0.03"),
    ("[imagination]\nworkers = 2.5\n", "imagination.workers: Input should be a valid integer"),
    ('[run]\nseed = "3"\n', "run.seed: Input should be a valid integer"),
    (
        "[arena]\nhumanoid_start_x_m = 5.0\n",
        "arena: humanoid_start_x_m, humanoid_start_y_m: (5, 0) m is outside",
    ),
    ("[arena]\nx_min_m = 3.0\n", "arena: x_min_m < x_max_m and y_min_m < y_max_m are needed"),
    ("[tre]\nassistance = true\n", "tre: unknown key (did you mean tree?)"),
    ('[robots]\ncell_file = "c.json"\ncell = {}\n', "robots: cell_file and cell: give one"),
    ('[robots.cell]\nnao_url = "tcp://nao:9559"\n', "robots.cell: missing field panda_host"),
    ("[tree\nassistance = true\n", "not valid TOML"),
    ("tree = 3\n", "tree: Input should be a valid dictionary"),
]


@pytest.mark.parametrize(("text", "named"), BAD, ids=[named[:40] for _, named in BAD])
def test_a_bad_configuration_exits_2_with_one_line_naming_it(tmp_path, capsys, text, named):
    path = tmp_path / "mission.toml"
    path.write_text(text)
    assert cli.main(["config", "--show", "--config", str(path)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == "", captured.err
    assert lines[0].startswith(f"bearchair: {path}: ") and named in lines[0], lines[0]


def test_run_refuses_a_bad_configuration_before_anything_runs(tmp_path, capsys):
    path = tmp_path / "mission.toml"
    path.write_text("[outputs]\nrecrod = true\n")
    out = tmp_path / "run"
    assert cli.main(["run", "--config", str(path), "--out", str(out)]) == 2
    assert "outputs.recrod: unknown key (did you mean record?)" in capsys.readouterr().err
    assert not out.exists()


def test_flags_override_the_file_and_set_any_key(tmp_path):
    path = tmp_path / "mission.toml"
    path.write_text('[run]\nseed = 3\nhelper = "ignores"\n[tree]\nmax_rotations = 2\n')
    args = cli.build_parser().parse_args(
        ["run", "--config", str(path), "--seed", "5", "--set", "tree.assistance=false"]
    )
    config = mission_from_args(args)
    assert (config.run.seed, config.run.helper) == (5, "ignores")
    assert config.tree.options() == TreeOptions(assistance=False, max_rotations=2)


def test_config_show_prints_the_resolved_configuration(capsys):
    argv = ["config", "--show", "--config", str(EXAMPLE), "--tree", "x:y", "--set", "run.seed=9"]
    assert cli.main(argv) == 0
    shown = json.loads(capsys.readouterr().out)
    assert shown["run"]["seed"] == 9 and shown["tree"]["factory"] == "x:y"
    assert parse_mission_config(shown) == parse_mission_config(shown)  # round-trips


def test_a_wrong_set_is_one_line():
    assert parse_assignment("scan.views=[0, 1]") == ("scan.views", [0, 1])
    assert parse_assignment("tree.factory=my_trees:build") == ("tree.factory", "my_trees:build")
    assert cli.main(["config", "--show", "--set", "run.sede=1"]) == 2
    assert cli.main(["config", "--show", "--set", "novalue"]) == 2


def test_relative_paths_are_relative_to_the_file(tmp_path):
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "mission.toml"
    path.write_text('[run]\nchair = "chair.obj"\n')
    assert load_mission_config(path).run.chair == tmp_path / "sub" / "chair.obj"


def test_the_run_record_holds_the_resolved_configuration(tmp_path):
    config = parse_mission_config({"tree": {"max_rotations": 2}}).run_config(tmp_path)
    saved = json.loads(write_config(config).read_text())
    assert saved["tree"]["max_rotations"] == 2 and saved["outputs"]["out_dir"] == str(tmp_path)
    assert (tmp_path / CONFIG_FILE).is_file()
    assert parse_mission_config(saved).run_config(tmp_path).tree_options == config.tree_options


def test_the_record_masks_an_inline_password(tmp_path):
    from tests.helpers.cells import GOOD_CELL

    cell = {
        **GOOD_CELL,
        "nao_url": "tcps://nao.local:9503",
        "nao_user": "nao",
        "nao_password": "pw",
    }
    config = parse_mission_config({"robots": {"cell": cell}}).run_config(tmp_path)
    assert config.resolved is not None
    assert config.resolved["robots"]["cell"]["nao_password"] == "***"


@pytest.mark.slow
def test_the_tuned_parameters_reach_the_default_skills(tmp_path):
    from bearchair.skills.default_skills import DefaultSkills

    raw = {
        "scan": {"views": [0, 2, 4, 6, 8], "voxel_size_m": 0.01},
        "imagination": {"workers": 1, "max_drop_time_s": 1.5, "drop_clearance_m": 0.1},
    }
    run = parse_mission_config(raw).run_config(tmp_path)
    skills = DefaultSkills(run.imagination_workers, run.skill_parameters)
    scan = skills.scan_chair.keywords  # pyright: ignore[reportFunctionMemberAccess]
    assert scan["views"] == (0, 2, 4, 6, 8) and scan["config"].voxel_size_m == 0.01
    settings = skills.imagine_sitting.keywords["settings"]
    assert (settings.max_time_s, settings.drop_clearance_m) == (1.5, 0.1)
    assert skills.imagine_sitting.keywords["workers"] == 1
