"""What one mission run is asked to do."""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any, Literal, cast

from bearchair.core.arena import DEFAULT_ARENA, Arena
from bearchair.core.errors import ChairSetError
from bearchair.core.userfiles import load_user_json, printable
from bearchair.skills.imagination import DEFAULT_WORKERS
from bearchair.skills.parameters import SkillParameters
from bearchair.trees.options import TreeOptions

logger = logging.getLogger(__name__)

Placement = Literal["accessible", "inaccessible"]
HelperMode = Literal["obeys", "disobeys", "ignores"]


@dataclass(frozen=True)
class RunConfig:
    """One run of the mission.

    Attributes:
        chair_path: the chair mesh; None for the chair made of boxes the project ships.
        placement: how the simulated chair is placed relative to the humanoid.
        helper: how the simulated helper reacts to instructions.
        seed: seeds everything random, in the world and in the skills.
        gui: show the pybullet GUI.
        out_dir: where the run record goes.
        mute: print instructions instead of speaking them.
        timeout_s: wall time after which the mission is stopped as failed.
        arena: the workspace layout.
        snapshots: in simulation, save a picture whenever a stage ends.
        record: write a Rerun recording, ``out_dir/mission.rrd``
            (:mod:`bearchair.executive.recording.mission_recording`).
        live: stream to a Rerun viewer while running: ``"spawn"``, ``"web"`` or a URL.
        bind: the address a live viewer listens on (loopback unless opened, ``--bind``).
        imagination_workers: processes the imagination's drops run in (1: the run's own;
            the result is the same for any number).
        tree_options: how the tree is composed (assistance, rotations, re-scan, looks).
        tree_spec: which tree (``--tree``: a name, ``module:factory`` or an XML file),
            recorded with the run; the factory itself is passed to the run.
        skill_parameters: the scan's and the imagination's tuned parameters.
        skill_plugins: ``bearchair.skills`` plug-ins stacked over the default skills.
        tick_period_s: wall time between two ticks of the tree.
        resolved: the mission configuration this came from, as JSON
            (``bearchair.executive.mission_config``), written to the run record; None:
            the record holds these fields.
        groot2_port: publish the running tree to Groot2 on this port and the next
            (``bearchair.executive.groot2``); None: not published.
        groot2_bind: the address Groot2's ports listen on (``*``: BT.CPP's own publisher,
            every interface).
    """

    chair_path: Path | None = None
    placement: Placement = "accessible"
    helper: HelperMode = "obeys"
    seed: int = 0
    gui: bool = False
    out_dir: Path = Path("runs/latest")
    mute: bool = False
    timeout_s: float = 900.0
    arena: Arena = field(default=DEFAULT_ARENA)
    snapshots: bool = False
    record: bool = False
    live: str | None = None
    bind: str = "127.0.0.1"
    imagination_workers: int = DEFAULT_WORKERS
    tree_options: TreeOptions = field(default_factory=TreeOptions)
    tree_spec: str = "mission"
    skill_parameters: SkillParameters = field(default_factory=SkillParameters)
    skill_plugins: tuple[str, ...] = ()
    tick_period_s: float = 0.05
    resolved: dict[str, Any] | None = None

    def record_json(self) -> dict[str, Any]:
        """What the run record keeps of the configuration: ``resolved`` when the run
        came from a mission configuration, else these fields."""
        if self.resolved is not None:
            return self.resolved
        return {
            item.name: _jsonable(getattr(self, item.name))
            for item in fields(self)
            if item.name != "resolved"
        }

    groot2_port: int | None = None
    groot2_bind: str = "127.0.0.1"

    def chair_name(self) -> str:
        return self.chair_path.name if self.chair_path else "box-chair (built in)"

    def to_payload(self) -> dict[str, Any]:
        """The JSON a run started in another process gets (a trial worker, a bench's
        fork): the fields a campaign or a bench chooses, by the names of
        ``bearchair.evaluation.protocol.TrialSpec.to_payload`` (``tree`` is
        :attr:`tree_spec`). The rest keep their defaults there (:meth:`from_payload`)."""
        return {
            "chair_path": None if self.chair_path is None else str(self.chair_path),
            "placement": self.placement,
            "helper": self.helper,
            "seed": self.seed,
            "out_dir": str(self.out_dir),
            "timeout_s": self.timeout_s,
            "record": self.record,
            "imagination_workers": self.imagination_workers,
            "tree": self.tree_spec,
            "mute": self.mute,
        }

    @classmethod
    def from_payload(cls, payload: dict[str, Any]) -> RunConfig:
        """The run a :meth:`to_payload` JSON (or a trial's) describes: a key left out
        keeps the default, a key not of the run (``trial_index``, a bench's ``label``)
        is ignored."""
        base = cls()
        chair = payload.get("chair_path")
        return cls(
            chair_path=Path(chair) if chair else None,
            placement=cast(Placement, str(payload.get("placement", base.placement))),
            helper=cast(HelperMode, str(payload.get("helper", base.helper))),
            seed=int(payload.get("seed", base.seed)),
            out_dir=Path(payload.get("out_dir", base.out_dir)),
            timeout_s=float(payload.get("timeout_s", base.timeout_s)),
            record=bool(payload.get("record", base.record)),
            imagination_workers=int(payload.get("imagination_workers", base.imagination_workers)),
            tree_spec=str(payload.get("tree", base.tree_spec)),
            mute=bool(payload.get("mute", base.mute)),
        )


def _jsonable(value: Any) -> Any:
    if is_dataclass(value) and not isinstance(value, type):
        return asdict(value)
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, tuple) and hasattr(value, "_asdict"):  # Arena, Box2D, SE2Pose
        named: Any = value
        return {key: _jsonable(item) for key, item in named._asdict().items()}
    if isinstance(value, tuple | list):
        return [_jsonable(item) for item in value]
    return value


def front_yaw_from_manifest(chair_path: Path) -> float | None:
    """The chair's sitting direction (degrees) from a ``manifest.json`` beside it, if any.

    Only the simulated world uses this, to place the chair accessibly or not; the
    mission itself never sees it. An unreadable manifest or an entry whose
    ``front_yaw_deg`` is not a finite number is ignored with a warning (the world then
    places the chair with a random yaw and says so).
    """
    manifest = chair_path.parent / "manifest.json"
    if not manifest.is_file():
        return None
    try:
        entries = load_user_json(manifest, "manifest", ChairSetError).get("meshes", [])
        entry = next(
            (e for e in entries if isinstance(e, dict) and e.get("file") == chair_path.name),
            None,
        )
    except (ChairSetError, AttributeError, TypeError) as error:
        logger.warning("ignoring unreadable %s: %s", printable(manifest), printable(error))
        return None
    if entry is None:
        return None
    front = entry.get("front_yaw_deg")
    if front is None:
        return None
    if isinstance(front, bool) or not isinstance(front, int | float) or not math.isfinite(front):
        logger.warning(
            "ignoring %s's front_yaw_deg %r in %s: not a number of degrees",
            chair_path.name,
            front,
            manifest,
        )
        return None
    return float(front)
