"""Which trials a campaign runs: the chairs of a folder and the paper's protocol.

The paper (Table 1) tests each chair in 6 trials: 3 accessible placements, 2
inaccessible placements with a helper who obeys, and 1 inaccessible placement with a
helper who disobeys the first instruction. Each trial's seed is derived from the
campaign seed, the chair's file name and the trial's index with SHA-256, so it is the
same in every process and on every machine (Python's ``hash()`` is salted per process).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any, NamedTuple

from bearchair.core.errors import ChairSetError
from bearchair.core.meshes import SUPPORTED_SUFFIXES
from bearchair.core.userfiles import load_user_json, printable
from bearchair.skills.imagination import DEFAULT_WORKERS

EXPERIMENTS = ("accessible", "inaccessible_obeys", "inaccessible_disobeys")
"""The three experiments of the paper's Table 1, in its row order."""

EXPERIMENT_LABELS = {
    "accessible": "Accessible",
    "inaccessible_obeys": "Inaccessible + Human Obeys",
    "inaccessible_disobeys": "Inaccessible + Human Disobeys",
}

EXPERIMENT_SETTINGS = {
    "accessible": ("accessible", "obeys"),
    "inaccessible_obeys": ("inaccessible", "obeys"),
    "inaccessible_disobeys": ("inaccessible", "disobeys"),
}
"""Experiment -> (placement, helper) given to the simulated world."""

PROTOCOLS: dict[str, tuple[str, ...]] = {
    "paper": ("accessible",) * 3 + ("inaccessible_obeys",) * 2 + ("inaccessible_disobeys",),
}
"""Protocol name -> the experiment of each trial index, per chair."""


SEAT_KINDS = frozenset({"chair", "sofa", "stool", "bench"})
"""The manifest kinds that are seats a child sits on. The paper's chairs afford sitting
by the interaction-based definition (a seat at sitting height with the back supported);
a campaign also needs a front to place the chair accessibly or not, so a seat takes part
only with a ``front_yaw_deg`` (a stool or a bench without a back has none). Every other
kind (``table``, ``box``, ``shelf``, ``cabinet``, ``toy``, any kind not listed here) is
not a chair, front or not: skipped with the reason. An entry without ``kind`` is a chair
(manifests written before kinds existed)."""

DEFAULT_KIND = "chair"
"""The kind of a manifest entry that names none."""


class ChairEntry(NamedTuple):
    """A chair that takes part in the campaign.

    Attributes:
        path: the mesh file.
        kind: the manifest's kind, one of :data:`SEAT_KINDS`.
        front_yaw_deg: the manifest's sitting direction in the mesh frame (degrees), if any.
        seat_height_m: the manifest's seat height (m) where it gives one: for the report's
            refusals against the reach model, never for the mission.
        style: the manifest's style ("folding", "lounge", ...) where it gives one.
    """

    path: Path
    kind: str
    front_yaw_deg: float | None
    seat_height_m: float | None = None
    style: str | None = None

    @property
    def name(self) -> str:
        return self.path.name


class SkippedChair(NamedTuple):
    """A mesh of the folder that does not take part, and why."""

    name: str
    reason: str


class TrialSpec(NamedTuple):
    """One trial of a campaign.

    Attributes:
        chair: the chair's file name (the records' chair column).
        chair_path: the mesh file.
        trial_index: the trial's index for this chair (0..5 in the paper protocol).
        experiment: one of :data:`EXPERIMENTS`.
        placement: "accessible" or "inaccessible".
        helper: "obeys" or "disobeys".
        seed: the trial's seed (world and skills).
    """

    chair: str
    chair_path: Path
    trial_index: int
    experiment: str
    placement: str
    helper: str
    seed: int

    @property
    def key(self) -> tuple[str, str, str, int, int]:
        """What identifies a finished trial in the records (resume skips it)."""
        return (self.chair, self.placement, self.helper, self.trial_index, self.seed)

    @property
    def label(self) -> str:
        return f"{self.chair} #{self.trial_index} {self.experiment} seed {self.seed}"

    def run_dir_name(self) -> str:
        """The trial's run record directory, relative to the campaign's runs folder."""
        return f"{Path(self.chair).stem}/t{self.trial_index}-{self.experiment}-seed{self.seed}"

    def to_payload(
        self,
        out_dir: Path,
        timeout_s: float,
        record: bool = False,
        imagination_workers: int = DEFAULT_WORKERS,
    ) -> dict[str, Any]:
        """The JSON the trial worker gets on its command line."""
        return {
            "record": record,
            "imagination_workers": imagination_workers,
            "chair_path": str(self.chair_path),
            "placement": self.placement,
            "helper": self.helper,
            "seed": self.seed,
            "trial_index": self.trial_index,
            "out_dir": str(out_dir),
            "timeout_s": timeout_s,
        }


def trial_seed(campaign_seed: int, chair_name: str, trial_index: int) -> int:
    """A 31-bit seed from SHA-256 of ``"<campaign_seed>/<chair_name>/<trial_index>"``."""
    text = f"{campaign_seed}/{chair_name}/{trial_index}".encode()
    return int.from_bytes(hashlib.sha256(text).digest()[:4], "big") & 0x7FFFFFFF


def read_manifest(chairs_dir: Path) -> dict[str, dict[str, Any]] | None:
    """``manifest.json``'s entries by file name, or None when the folder has none.

    Raises:
        ChairSetError: the manifest exists but is not valid JSON of the expected shape
            (an object whose ``meshes`` is a list of objects, each with a ``file``
            name); entries' values are checked by :func:`manifest_entry_problem`.
    """
    manifest_path = chairs_dir / "manifest.json"
    if not manifest_path.exists() and not manifest_path.is_symlink():
        return None
    document = load_user_json(manifest_path, "manifest", ChairSetError)
    where = printable(manifest_path)
    entries = document.get("meshes") if isinstance(document, dict) else None
    if not isinstance(entries, list):
        raise ChairSetError(
            f'{where}: expected an object with a "meshes" list, as in ../shared/chairs'
        )
    if not entries:
        raise ChairSetError(f'{where}: its "meshes" list is empty; list each mesh of the folder')
    by_name: dict[str, dict[str, Any]] = {}
    numbers: dict[str, int] = {}
    for number, entry in enumerate(entries):
        if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
            raise ChairSetError(f'{where}: meshes[{number}] is not an object with a "file" name')
        name = entry["file"]
        if name in by_name:
            raise ChairSetError(
                f"{where}: meshes[{numbers[name]}] and meshes[{number}] both list "
                f"{printable(name)}; keep one"
            )
        by_name[name], numbers[name] = entry, number
    return by_name


def manifest_entry_problem(entry: dict[str, Any]) -> str | None:
    """What is wrong with a manifest entry's values, or None.

    ``front_yaw_deg`` must be a finite number of degrees or null; ``kind`` and ``style``
    strings; ``seat_height_m`` a positive number of metres or null. Other fields are
    tolerated.
    """
    front = entry.get("front_yaw_deg")
    if front is not None and not _finite_number(front):
        return f"front_yaw_deg is {json.dumps(front)[:40]}, not a number of degrees or null"
    seat = entry.get("seat_height_m")
    if seat is not None and not (_finite_number(seat) and seat > 0.0):
        return f"seat_height_m is {json.dumps(seat)[:40]}, not a positive number of metres or null"
    for field in ("kind", "style"):
        if field in entry and entry[field] is not None and not isinstance(entry[field], str):
            return f"{field} is {json.dumps(entry[field])[:40]}, not a string"
    return None


def _finite_number(value: Any) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)


def discover_chairs(
    chairs_dir: Path,
    max_chairs: int | None = None,
    *,
    check_meshes: bool = False,
    skip_bad: bool = False,
) -> tuple[list[ChairEntry], list[SkippedChair]]:
    """The chairs of a folder that take part, in sorted file order, and those skipped.

    Every file with a supported mesh suffix is a candidate. The folder must have a
    ``manifest.json``: the simulated world needs each chair's front to place it
    accessibly or not (without it "inaccessible" trials would be placed at random).
    Only seats (:data:`SEAT_KINDS`) with a front (``front_yaw_deg`` not null) take part. ``max_chairs``
    keeps the first N that take part (deterministic), the rest are listed as skipped.

    Args:
        chairs_dir: the folder.
        max_chairs: keep the first N chairs that take part.
        check_meshes: also load and check each taking part (``load_chair_mesh``), so a
            bad file is found before the first trial instead of trial by trial.
        skip_bad: list bad entries (manifest values, meshes) as skipped instead of
            raising; they do not count toward ``max_chairs``.

    Raises:
        BadChairsError: bad entries (one line each in ``problems``), unless ``skip_bad``.
        ChairSetError: the folder is missing, holds no supported mesh or no manifest,
            or none takes part.
    """
    meshes = _mesh_files(chairs_dir)
    manifest = read_manifest(chairs_dir)
    if manifest is None:
        raise ChairSetError(
            f"{chairs_dir}: no manifest.json; trials need each chair's front_yaw_deg to place "
            "it accessibly or not (see ../shared/chairs/README.md for the format)"
        )
    chosen: list[ChairEntry] = []
    skipped: list[SkippedChair] = []
    problems: list[str] = []
    for path in meshes:
        verdict = _verdict(path, manifest, chairs_dir, len(chosen), max_chairs, check_meshes)
        if isinstance(verdict, ChairEntry):
            chosen.append(verdict)
        elif isinstance(verdict, SkippedChair):
            skipped.append(verdict)
        elif skip_bad:
            skipped.append(SkippedChair(path.name, f"unusable: {verdict}"))
        else:
            problems.append(verdict)
    if problems:
        raise BadChairsError(problems)
    if not chosen:
        reasons = "; ".join(f"{printable(s.name)}: {s.reason}" for s in skipped[:3])
        more = f"; and {len(skipped) - 3} more" if len(skipped) > 3 else ""
        raise ChairSetError(
            f"{printable(chairs_dir)}: none of its {len(meshes)} meshes takes part "
            f"({reasons}{more})"
        )
    return chosen, skipped


def _mesh_files(chairs_dir: Path) -> list[Path]:
    """The folder's files with a supported mesh suffix, sorted.

    Raises:
        ChairSetError: the folder is missing, unlistable or holds no such file.
    """
    if not chairs_dir.exists():
        raise ChairSetError(f"{chairs_dir}: no such directory")
    if not chairs_dir.is_dir():
        raise ChairSetError(f"{chairs_dir}: not a directory")
    try:
        meshes = sorted(
            p
            for p in chairs_dir.iterdir()
            if p.suffix.lower() in SUPPORTED_SUFFIXES and not p.is_dir()
        )
    except OSError as error:
        raise ChairSetError(f"{chairs_dir}: cannot list it ({error.strerror or error})") from error
    if not meshes:
        raise ChairSetError(
            f"{chairs_dir}: no chair meshes ({', '.join(SUPPORTED_SUFFIXES)}) in this directory"
        )
    return meshes


def _verdict(
    path: Path,
    manifest: dict[str, dict[str, Any]],
    chairs_dir: Path,
    chosen_so_far: int,
    max_chairs: int | None,
    check_meshes: bool,
) -> ChairEntry | SkippedChair | str:
    """What one mesh of the folder is: a chair that takes part, a mesh skipped, or (a
    ``str``) the one-line problem of an unusable manifest entry or mesh."""
    from bearchair.core.meshes import MeshLoadError, load_chair_mesh

    if path.name not in manifest:
        same = [name for name in manifest if name.casefold() == path.name.casefold()]
        hint = f" (it lists {printable(same[0])}: the names differ in case)" if same else ""
        return SkippedChair(path.name, f"not in manifest.json{hint}")
    info = manifest[path.name]
    problem = manifest_entry_problem(info)
    if problem is not None:
        return f"{chairs_dir / 'manifest.json'}: {path.name}: {problem}"
    front = info.get("front_yaw_deg")
    kind = info.get("kind") or DEFAULT_KIND
    if kind not in SEAT_KINDS:
        return SkippedChair(
            path.name, f"not a chair: kind {kind!r} (seats: {', '.join(sorted(SEAT_KINDS))})"
        )
    if front is None:
        return SkippedChair(path.name, f"{kind} without a front (front_yaw_deg null)")
    if max_chairs is not None and chosen_so_far >= max_chairs:
        return SkippedChair(path.name, f"beyond --max-chairs {max_chairs}")
    if check_meshes:
        try:
            load_chair_mesh(path)
        except MeshLoadError as error:
            return str(error)
    seat = info.get("seat_height_m")
    return ChairEntry(
        path, kind, float(front), None if seat is None else float(seat), info.get("style")
    )


class BadChairsError(ChairSetError):
    """Some chairs of the campaign are unusable; ``problems`` has one line per chair."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__(problems[-1])
        self.problems = problems


def expand_protocol(
    chairs: list[ChairEntry], protocol: str = "paper", campaign_seed: int = 0
) -> list[TrialSpec]:
    """Every trial of the campaign, chair by chair, in trial-index order.

    Raises:
        ValueError: unknown protocol.
    """
    if protocol not in PROTOCOLS:
        raise ValueError(f"unknown protocol {protocol!r} (known: {', '.join(PROTOCOLS)})")
    trials = []
    for chair in chairs:
        for index, experiment in enumerate(PROTOCOLS[protocol]):
            placement, helper = EXPERIMENT_SETTINGS[experiment]
            trials.append(
                TrialSpec(
                    chair=chair.name,
                    chair_path=chair.path,
                    trial_index=index,
                    experiment=experiment,
                    placement=placement,
                    helper=helper,
                    seed=trial_seed(campaign_seed, chair.name, index),
                )
            )
    return trials
