"""What crosses the network between a campaign's head and Ray's nodes.

No filesystem is shared: the head ships the ``bearchair`` package (as real files: in a
checkout ``bearchair/<room>`` are symbolic links) and each trial's chair (its mesh and
its manifest entry) and ``--tree`` file, if any, to the node that runs the trial; the node sends the trial's run
folder back as one gzipped tar, which the head unpacks under its own ``--out``.
"""

from __future__ import annotations

import io
import json
import shutil
import sys
import tarfile
import tempfile
from pathlib import Path
from typing import Any

from bearchair.core.provenance import SHIPPED_FILE, bearchair_version, git_commit

MANIFEST_NAME = "manifest.json"


def package_dir() -> Path:
    """The folder of the ``bearchair`` package this process imported (loaded already: it
    is this module's parent; looked up, not imported, which the layering forbids)."""
    top = sys.modules[__name__.split(".", 1)[0]]
    return Path(str(top.__file__)).resolve().parent


def stage_package(into: Path) -> Path:
    """Copies the ``bearchair`` package into ``into/bearchair``, links followed.

    Ray zips a ``py_modules`` folder as it finds it; a checkout's ``bearchair/<room>``
    links would reach the nodes as links to folders they do not have, so the copy holds
    real files (byte caches left out), and :data:`~bearchair.core.provenance.SHIPPED_FILE`
    names the version and commit it was copied from.

    Returns:
        The copy's folder, for ``runtime_env={"py_modules": [...]}``.
    """
    target = Path(into) / "bearchair"
    shutil.copytree(
        package_dir(),
        target,
        symlinks=False,
        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", SHIPPED_FILE),
    )
    # The copy is neither installed nor a checkout: it says where it came from, so the
    # records the nodes write name the head's version and commit.
    shipped = {"bearchair": bearchair_version(), "git_commit": git_commit()}
    (target / SHIPPED_FILE).write_text(json.dumps(shipped))
    return target


def chair_files(chair_path: str | Path | None) -> dict[str, bytes]:
    """The chair's mesh and its manifest entry as bytes (the node has neither).

    The manifest shipped holds only this chair's entry: the simulated world reads the
    chair's front from it to place the chair (``executive.config.front_yaw_from_manifest``).
    None (the built-in box chair) ships nothing.
    """
    if not chair_path:
        return {}
    path = Path(chair_path)
    files = {path.name: path.read_bytes()}
    manifest = path.parent / MANIFEST_NAME
    if manifest.is_file():
        try:
            entries = json.loads(manifest.read_text(encoding="utf-8")).get("meshes", [])
            mine = [e for e in entries if isinstance(e, dict) and e.get("file") == path.name]
        except (OSError, ValueError, AttributeError):
            mine = []  # unreadable: the trial goes on as it would here, without a front
        files[MANIFEST_NAME] = json.dumps({"meshes": mine}).encode()
    return files


def tree_file(tree_spec: str | None) -> dict[str, bytes]:
    """A ``--tree`` SPEC that is a BehaviorTree.CPP file, as bytes (the node has no copy);
    an entry point or ``module:factory`` ships nothing: it must be installed on the node."""
    if not tree_spec or not tree_spec.endswith(".xml"):
        return {}
    path = Path(tree_spec)
    return {path.name: path.read_bytes()}


def write_chair(files: dict[str, bytes], folder: Path) -> Path | None:
    """Writes :func:`chair_files`' (or :func:`tree_file`'s) files into ``folder``; returns
    the mesh's (the tree's) path (None: none)."""
    folder.mkdir(parents=True, exist_ok=True)
    mesh = None
    for name, data in files.items():
        if Path(name).name != name:
            raise ValueError(f"a shipped chair file must be a bare name, not {name!r}")
        (folder / name).write_bytes(data)
        if name != MANIFEST_NAME:
            mesh = folder / name
    return mesh


def pack_folder(folder: Path) -> bytes:
    """The folder's files as a gzipped tar (paths relative to it); empty folder: empty tar."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as archive:
        if folder.is_dir():
            for path in sorted(folder.rglob("*")):
                archive.add(path, arcname=str(path.relative_to(folder)), recursive=False)
    return buffer.getvalue()


def unpack_folder(data: bytes, folder: Path) -> list[Path]:
    """Unpacks :func:`pack_folder`'s bytes into ``folder``; returns the files written.

    Raises:
        tarfile.TarError: the bytes are not such a tar, or a member would land outside
            ``folder`` (the ``data`` filter refuses absolute paths, ``..`` and links out).
    """
    folder.mkdir(parents=True, exist_ok=True)
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as archive:
        members = archive.getmembers()
        archive.extractall(folder, filter="data")
    return [folder / m.name for m in members if m.isfile()]


class TrialScratch:
    """A node's temporary folder for one trial: the shipped chair and the run folder.

    Use as a context manager; the folder is removed on exit, whatever happened.
    """

    def __init__(self) -> None:
        self.root = Path(tempfile.mkdtemp(prefix="bearchair-trial-"))
        self.run_dir = self.root / "run"

    def payload_here(
        self, payload: dict[str, Any], chair: dict[str, bytes], tree: dict[str, bytes] | None = None
    ) -> dict[str, Any]:
        """The head's payload with this node's chair path, tree file and run folder."""
        mesh = write_chair(chair, self.root / "chair")
        here = {
            **payload,
            "chair_path": str(mesh) if mesh is not None else payload.get("chair_path"),
            "out_dir": str(self.run_dir),
        }
        if tree:
            here["tree"] = str(write_chair(tree, self.root / "tree"))
        return here

    def __enter__(self) -> TrialScratch:
        return self

    def __exit__(self, *exc: object) -> None:
        shutil.rmtree(self.root, ignore_errors=True)
