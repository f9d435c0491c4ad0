"""What software made a record: bearchair's version, its git commit, the key dependencies.

Every ``summary.json`` and every row of a trials database carries :func:`software_versions`,
so a result can be traced to the code and the libraries that produced it.
"""

from __future__ import annotations

import functools
import json
import subprocess
from importlib import metadata
from pathlib import Path
from typing import Any

KEY_DISTRIBUTIONS = (
    "py-trees",
    "pybullet",
    "open3d",
    "trimesh",
    "ompl",
    "python-fcl",
    "casadi",
    "opencv-python-headless",
    "numpy",
    "scipy",
)
"""The libraries whose version can change a mission's outcome (physics, geometry, solvers)."""

GIT_TIMEOUT_S = 2.0
"""How long ``git`` may take to name the commit before the record goes without it."""


def distribution_version(name: str) -> str | None:
    """The installed version of a distribution, or None where it is not installed."""
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


SHIPPED_FILE = "shipped_from.json"
"""In a copy of the package shipped to other machines (a Ray cluster's nodes,
``bearchair.evaluation.shipping``): the version and commit of the code it was copied
from, which the copy, neither installed nor a checkout, cannot tell by itself."""


@functools.cache
def shipped_from() -> dict[str, Any] | None:
    """:data:`SHIPPED_FILE` beside this package's subpackages, or None (not a shipped copy)."""
    try:
        shipped = json.loads((Path(__file__).resolve().parent.parent / SHIPPED_FILE).read_text())
    except (OSError, ValueError):
        return None
    return shipped if isinstance(shipped, dict) else None


def bearchair_version() -> str:
    """bearchair's installed version (``0+unknown`` for a checkout that was never installed);
    a shipped copy's is the one it was copied from."""
    shipped = shipped_from()
    if shipped is not None and isinstance(shipped.get("bearchair"), str):
        return shipped["bearchair"]
    return distribution_version("bearchair") or "0+unknown"


@functools.cache
def git_commit() -> str | None:
    """The commit of the checkout this code runs from (``+dirty`` when it has changes).

    None where the code is not in a git checkout (an installed wheel) or git is missing;
    a shipped copy's (:data:`SHIPPED_FILE`) is the one of the code it was copied from.
    The package folder is resolved first: in a checkout ``bearchair/<room>`` links to
    ``<checkout>/<room>``.
    """
    shipped = shipped_from()
    if shipped is not None:
        return shipped.get("git_commit")
    checkout = Path(__file__).resolve().parent.parent
    if not (checkout / ".git").exists():
        return None
    try:
        head = subprocess.run(
            ["git", "-C", str(checkout), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            timeout=GIT_TIMEOUT_S,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(checkout), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=GIT_TIMEOUT_S,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return f"{head}+dirty" if dirty else head


@functools.cache
def _dependency_versions() -> tuple[tuple[str, str | None], ...]:
    return tuple((name, distribution_version(name)) for name in KEY_DISTRIBUTIONS)


def software_versions() -> dict[str, Any]:
    """``{"bearchair": version, "git_commit": sha or None, "dependencies": {name: version}}``."""
    return {
        "bearchair": bearchair_version(),
        "git_commit": git_commit(),
        "dependencies": dict(_dependency_versions()),
    }


def version_line() -> str:
    """One line for ``bearchair --version``: the version and, from a checkout, the commit."""
    commit = git_commit()
    where = (
        f" (commit {commit[:12]}{'+dirty' if commit.endswith('+dirty') else ''})" if commit else ""
    )
    return f"bearchair {bearchair_version()}{where}"
