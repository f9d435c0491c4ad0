"""The documentation: the site builds with no warning, the tutorial's commands work as
written, and the README stays a short front door."""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
README_MAX_LINES = 120


def shell_commands(markdown: str) -> list[str]:
    """Every command of the page's ```sh blocks, in order (comments and blanks dropped)."""
    commands = []
    for block in re.findall(r"^```sh\n(.*?)^```", markdown, flags=re.S | re.M):
        for line in block.splitlines():
            line = line.split(" #", 1)[0].strip()
            if line and not line.startswith("#"):
                commands.append(line)
    return commands


def test_shell_commands_are_read_from_sh_blocks_only():
    page = "x\n```sh\nbearchair a  # note\n\n# c\nbearchair b\n```\n```text\nnot me\n```\n"
    assert shell_commands(page) == ["bearchair a", "bearchair b"]


@pytest.mark.slow
def test_the_site_builds_with_no_warning(tmp_path):
    pytest.importorskip("mkdocs")
    pytest.importorskip("material")
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    assert done.returncode == 0, done.stderr[-3000:]
    cli_page = (tmp_path / "cli" / "index.html").read_text()
    assert "bearchair run" in cli_page and "--overwrite" in cli_page  # generated, not empty


@pytest.mark.slow
def test_every_tutorial_command_runs_as_written(tmp_path):
    commands = shell_commands((DOCS / "tutorial.md").read_text())
    assert len(commands) >= 5
    executable = shutil.which("bearchair", path=str(Path(sys.executable).parent))
    assert executable, "the bearchair command is installed beside this Python"
    for command in commands:
        argv = shlex.split(command)
        assert argv[0] == "bearchair", f"the tutorial runs only bearchair commands: {command}"
        done = subprocess.run(
            [executable, *argv[1:]], cwd=tmp_path, capture_output=True, text=True, timeout=600
        )
        assert done.returncode == 0, f"{command}: exit {done.returncode}\n{done.stderr[-2000:]}"
    assert (tmp_path / "runs" / "first" / "summary.json").exists()
    assert (tmp_path / "runs" / "mission.svg").exists()


def test_the_readme_is_a_short_door_with_a_picture_and_the_two_commands():
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= README_MAX_LINES
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", readme)
    assert pictures and all((REPO / p).exists() for p in pictures)
    assert "make demo" in readme and "make test" in readme
    for link in re.findall(r"\]\((docs/[^)#]+)", readme):
        assert (REPO / link).exists(), link
