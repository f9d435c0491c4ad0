"""The distribution: one top-level import package, and a wheel that works outside the checkout."""

from __future__ import annotations

import json
import site
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    done = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(REPO)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    (path,) = out.glob("bearchair-*.whl")
    return path


def test_the_wheels_only_top_level_package_is_bearchair(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    top = {name.split("/")[0] for name in names if not name.split("/")[0].endswith(".dist-info")}
    assert top == {"bearchair"}
    for room in ("core", "hardware", "skills", "behaviours", "trees", "executive", "evaluation"):
        assert f"bearchair/{room}/__init__.py" in names  # the links were followed
    assert "bearchair/py.typed" in names
    assert "bearchair/skills/planning/wholebody/reach_table.json" in names  # package data
    assert any(name.endswith("/licenses/LICENSE") for name in names)


@pytest.mark.slow
def test_a_fresh_venv_with_the_wheel_runs_the_mission_to_a_seated_bear(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    # The dependencies come from this environment (a .pth), bearchair only from the wheel.
    (site_dir,) = (venv / "lib").glob("python3.*/site-packages")
    (site_dir / "deps.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--no-deps", str(wheel)],
        check=True,
        timeout=300,
        capture_output=True,
    )
    where = subprocess.run(
        [str(python), "-c", "import bearchair.skills, sys; print(bearchair.skills.__file__)"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert Path(where).is_relative_to(site_dir)  # not the checkout
    version = subprocess.run(
        [str(venv / "bin" / "bearchair"), "--version"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert version.returncode == 0 and version.stdout.startswith("bearchair "), version.stderr
    run = subprocess.run(
        [str(venv / "bin" / "bearchair"), "run", "--mute", "--out", str(tmp_path / "run")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["outcome"] == "success" and summary["judgement"]["seated"]
