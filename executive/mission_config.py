"""The mission configuration file (``bearchair run --config mission.toml``), checked by pydantic.

One TOML file says everything a run is asked to do; every section and key is optional
(an empty file is the defaults, the same as ``bearchair run`` with no flags)::

    [tree]          which tree and how it is composed (TreeOptions)
    [run]           the chair, its placement, the helper, the seed
    [timeouts]      the mission's wall-time limit, the tick period
    [scan]          the views the arm visits, the reconstruction's voxel
    [imagination]   worker processes, the drops' stopping time and height
    [arena]         the workspace: walls, chair area, obstacles, the humanoid's start
    [skills]        bearchair.skills plug-ins stacked over the default skills
    [robots]        real robots: a cell file, or the cell inline ([robots.cell])
    [outputs]       the run folder, recordings, snapshots

Every key with a unit says it: ``_m`` metres, ``_s`` seconds, ``_deg`` degrees. A key
the schema does not know is an error (``extra="forbid"``): a misspelt or unit-less key
(``timeout = 60``) is refused with the nearest known name, never silently ignored.
Relative paths (``run.chair``, ``robots.cell_file``) are relative to the configuration
file; ``outputs.out_dir`` to the current folder, like ``--out``.

:func:`load_mission_config` raises :class:`bearchair.core.errors.ConfigError` with one
line naming the file and the field; ``bearchair config --schema`` prints the JSON Schema
(for editors), ``bearchair config --show`` the resolved configuration. The page
``docs/configuration.md`` describes every key.
"""

from __future__ import annotations

import argparse
import difflib
import math
import tomllib
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from bearchair.core.arena import DEFAULT_ARENA, Arena, Box2D
from bearchair.core.errors import ConfigError
from bearchair.core.se2 import SE2Pose
from bearchair.core.userfiles import MAX_JSON_DEPTH, nesting_depth, printable, read_user_text
from bearchair.executive.cli_types import MAX_SEED
from bearchair.executive.config import RunConfig
from bearchair.executive.viewer_links import LOOPBACK, bind_address
from bearchair.skills.imagination import DEFAULT_WORKERS
from bearchair.skills.parameters import MIN_SCAN_VIEWS, SCAN_VIEW_COUNT, SkillParameters
from bearchair.trees.options import MAX_LOOKS, TreeOptions


class _Section(BaseModel):
    # strict: TOML has types, so "no" is no boolean and "900" no number (an int is a float).
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class TreeSection(_Section):
    """``[tree]``: which tree runs (``--tree``) and how it is composed."""

    factory: str = Field(
        default="mission",
        min_length=1,
        description="a tree name (mission, or a bearchair.trees entry point), "
        "module:factory, or a BehaviorTree.CPP .xml file",
    )
    assistance: bool = Field(
        default=True, description="ask the helper to turn an inaccessible chair"
    )
    max_rotations: int = Field(default=3, ge=1, le=12, description="rotations asked for at most")
    rescan_fallback: bool = Field(
        default=True,
        description="scan and imagine a turned chair anew when ICP cannot measure the turn",
    )

    max_looks: int = Field(
        default=MAX_LOOKS,
        ge=0,
        le=12,
        description="looks from above when the imagination finds no sitting on the scan",
    )

    def options(self) -> TreeOptions:
        return TreeOptions(
            self.assistance, self.max_rotations, self.rescan_fallback, self.max_looks
        )


class RunSection(_Section):
    """``[run]``: what the simulated world holds, and the seed."""

    seed: int = Field(default=0, ge=0, le=MAX_SEED, description="seeds everything random")
    chair: Path | None = Field(
        default=None, strict=False, description="chair mesh; none: the built-in box chair"
    )
    placement: Literal["accessible", "inaccessible"] = "accessible"
    helper: Literal["obeys", "disobeys", "ignores"] = "obeys"
    gui: bool = Field(default=False, description="watch in the pybullet GUI")
    mute: bool = Field(default=False, description="print instructions instead of speaking them")


class TimeoutsSection(_Section):
    """``[timeouts]``: wall-time limits (seconds)."""

    mission_s: float = Field(default=900.0, gt=0.0, le=86400.0, description="the whole mission")
    tick_period_s: float = Field(default=0.05, gt=0.0, le=1.0, description="between two ticks")


class ScanSection(_Section):
    """``[scan]``: the chair scan."""

    views: list[int] | None = Field(
        default=None,
        description=f"indices (0-{SCAN_VIEW_COUNT - 1}) of the scan configurations to visit, "
        f"in order, at least {MIN_SCAN_VIEWS}; none: all {SCAN_VIEW_COUNT}",
    )
    voxel_size_m: float | None = Field(
        default=None, ge=0.002, le=0.03, description="TSDF voxel edge; none: 8 mm"
    )

    @model_validator(mode="after")
    def _views_exist(self) -> ScanSection:
        if self.views is None:
            return self
        wrong = [view for view in self.views if not 0 <= view < SCAN_VIEW_COUNT]
        if wrong:
            raise ValueError(f"views: {wrong[0]} is not a view index 0-{SCAN_VIEW_COUNT - 1}")
        if len(set(self.views)) != len(self.views):
            raise ValueError("views: a view is listed twice")
        if len(self.views) < MIN_SCAN_VIEWS:
            raise ValueError(f"views: {len(self.views)} views, at least {MIN_SCAN_VIEWS} needed")
        return self


class ImaginationSection(_Section):
    """``[imagination]``: the simulated drops of the child-sized agent."""

    workers: int = Field(
        default=DEFAULT_WORKERS, ge=1, le=64, description="processes the drops run in"
    )
    max_drop_time_s: float | None = Field(
        default=None, ge=0.5, le=20.0, description="simulated seconds before a drop is stopped"
    )
    drop_clearance_m: float | None = Field(
        default=None, ge=0.02, le=0.5, description="drop height above the chair's box; none: 15 cm"
    )


class BoxSection(_Section):
    """An axis-aligned footprint (metres, world frame) and its height."""

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    height_m: float = Field(default=1.0, gt=0.0, le=3.0)

    @model_validator(mode="after")
    def _ordered(self) -> BoxSection:
        if not (self.x_min_m < self.x_max_m and self.y_min_m < self.y_max_m):
            raise ValueError("x_min_m < x_max_m and y_min_m < y_max_m are needed")
        return self

    def box(self) -> Box2D:
        return Box2D(self.x_min_m, self.x_max_m, self.y_min_m, self.y_max_m, self.height_m)

    @classmethod
    def of(cls, box: Box2D) -> BoxSection:
        return cls(
            x_min_m=box.x_min, x_max_m=box.x_max, y_min_m=box.y_min, y_max_m=box.y_max,
            height_m=box.height,
        )  # fmt: skip


_A = DEFAULT_ARENA


class ArenaSection(_Section):
    """``[arena]``: where the humanoid may walk, the chair area, obstacles (metres, degrees)."""

    x_min_m: float = Field(default=_A.x_min, ge=-10.0, le=10.0)
    x_max_m: float = Field(default=_A.x_max, ge=-10.0, le=10.0)
    y_min_m: float = Field(default=_A.y_min, ge=-10.0, le=10.0)
    y_max_m: float = Field(default=_A.y_max, ge=-10.0, le=10.0)
    chair_area: BoxSection = BoxSection.of(_A.chair_area)
    arm_base_x_m: float = Field(default=_A.arm_base_xy[0], ge=-10.0, le=10.0)
    arm_base_y_m: float = Field(default=_A.arm_base_xy[1], ge=-10.0, le=10.0)
    obstacles: list[BoxSection] = [BoxSection.of(box) for box in _A.obstacles]
    humanoid_start_x_m: float = Field(default=_A.humanoid_start.x, ge=-10.0, le=10.0)
    humanoid_start_y_m: float = Field(default=_A.humanoid_start.y, ge=-10.0, le=10.0)
    humanoid_start_yaw_deg: float = Field(
        default=math.degrees(_A.humanoid_start.theta), ge=-180.0, le=180.0
    )

    @model_validator(mode="after")
    def _consistent(self) -> ArenaSection:
        if not (self.x_min_m < self.x_max_m and self.y_min_m < self.y_max_m):
            raise ValueError("x_min_m < x_max_m and y_min_m < y_max_m are needed")
        if not self.arena().contains(self.humanoid_start_x_m, self.humanoid_start_y_m):
            raise ValueError(
                f"humanoid_start_x_m, humanoid_start_y_m: ({self.humanoid_start_x_m:g}, "
                f"{self.humanoid_start_y_m:g}) m is outside the arena x [{self.x_min_m:g}, "
                f"{self.x_max_m:g}], y [{self.y_min_m:g}, {self.y_max_m:g}] m"
            )
        return self

    def arena(self) -> Arena:
        return Arena(
            x_min=self.x_min_m,
            x_max=self.x_max_m,
            y_min=self.y_min_m,
            y_max=self.y_max_m,
            chair_area=self.chair_area.box(),
            arm_base_xy=(self.arm_base_x_m, self.arm_base_y_m),
            obstacles=tuple(box.box() for box in self.obstacles),
            humanoid_start=SE2Pose(
                self.humanoid_start_x_m,
                self.humanoid_start_y_m,
                math.radians(self.humanoid_start_yaw_deg),
            ),
        )


class SkillsSection(_Section):
    """``[skills]``: plug-ins of the ``bearchair.skills`` group, stacked in order."""

    plugins: list[str] = Field(default_factory=list, description="entry point names")


class RobotsSection(_Section):
    """``[robots]``: run on real robots; the cell file, or the cell inline (not both)."""

    cell_file: Path | None = Field(
        default=None, strict=False, description="a cell file (JSON/YAML)"
    )
    cell: dict[str, Any] | None = Field(
        default=None, description="the cell file's fields (executive/cell_config.py), inline"
    )

    @model_validator(mode="after")
    def _one_cell(self) -> RobotsSection:
        if self.cell_file is not None and self.cell is not None:
            raise ValueError("cell_file and cell: give one of them, not both")
        return self

    @property
    def used(self) -> bool:
        return self.cell_file is not None or self.cell is not None


class OutputsSection(_Section):
    """``[outputs]``: where the run record goes and what it holds."""

    out_dir: Path | None = Field(
        default=None, strict=False, description="run folder; none: runs/<time>-seed<N>"
    )
    overwrite: bool = Field(default=False, description="replace a run record already in out_dir")
    record: bool = Field(default=False, description="write a Rerun recording, mission.rrd")
    live: str | None = Field(
        default=None, description="stream to a Rerun viewer: spawn, web or a URL"
    )
    bind: str = Field(
        default=LOOPBACK,
        description="the IP address a live viewer listens on: 127.0.0.1 this machine only, "
        "0.0.0.0 every network",
    )
    snapshots: bool = Field(default=False, description="a picture whenever a stage ends")

    @model_validator(mode="after")
    def _bind_is_an_address(self) -> OutputsSection:
        try:
            bind_address(self.bind)
        except argparse.ArgumentTypeError as error:
            raise ValueError(f"bind: {error}") from None
        return self


class MissionConfig(_Section):
    """A whole mission configuration (see the module docstring)."""

    model_config = ConfigDict(
        extra="forbid", frozen=True, strict=True, title="bearchair mission configuration"
    )

    tree: TreeSection = TreeSection()
    run: RunSection = RunSection()
    timeouts: TimeoutsSection = TimeoutsSection()
    scan: ScanSection = ScanSection()
    imagination: ImaginationSection = ImaginationSection()
    arena: ArenaSection = ArenaSection()
    skills: SkillsSection = SkillsSection()
    robots: RobotsSection = RobotsSection()
    outputs: OutputsSection = OutputsSection()

    def run_config(self, out_dir: Path) -> RunConfig:
        """The :class:`RunConfig` of this configuration, its record holding this one."""
        resolved = self.model_copy(
            update={"outputs": self.outputs.model_copy(update={"out_dir": out_dir})}
        )
        return RunConfig(
            chair_path=self.run.chair,
            placement=self.run.placement,
            helper=self.run.helper,
            seed=self.run.seed,
            gui=self.run.gui,
            out_dir=out_dir,
            mute=self.run.mute,
            timeout_s=self.timeouts.mission_s,
            arena=self.arena.arena(),
            snapshots=self.outputs.snapshots,
            record=self.outputs.record,
            live=self.outputs.live,
            bind=self.outputs.bind,
            imagination_workers=self.imagination.workers,
            tree_options=self.tree.options(),
            tree_spec=self.tree.factory,
            skill_parameters=SkillParameters(
                scan_views=None if self.scan.views is None else tuple(self.scan.views),
                voxel_size_m=self.scan.voxel_size_m,
                max_drop_time_s=self.imagination.max_drop_time_s,
                drop_clearance_m=self.imagination.drop_clearance_m,
            ),
            skill_plugins=tuple(self.skills.plugins),
            tick_period_s=self.timeouts.tick_period_s,
            resolved=_masked(resolved.model_dump(mode="json")),
        )


def _masked(resolved: dict[str, Any]) -> dict[str, Any]:
    """The configuration for the run record: an inline cell's password masked."""
    cell = resolved.get("robots", {}).get("cell")
    if isinstance(cell, dict) and cell.get("nao_password"):
        cell["nao_password"] = "***"
    return resolved


def json_schema() -> dict[str, Any]:
    """The configuration's JSON Schema (``bearchair config --schema``)."""
    return MissionConfig.model_json_schema()


def load_mission_config(path: Path) -> MissionConfig:
    """Reads and checks a mission configuration (TOML).

    Raises:
        ConfigError: the file is missing, not TOML, or a field is wrong: one line naming
            the file and the field.
    """
    path = Path(path)
    text = read_user_text(path, "configuration", ConfigError)  # regular, bounded
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"{printable(path)}: not valid TOML ({printable(error)})") from error
    except RecursionError:
        raise ConfigError(f"{printable(path)}: not valid TOML (nested too deeply)") from None
    if nesting_depth(raw) > MAX_JSON_DEPTH:
        raise ConfigError(f"{printable(path)}: nested deeper than {MAX_JSON_DEPTH}")
    _resolve_paths(raw, path.parent)
    return parse_mission_config(raw, str(path))


def parse_mission_config(raw: dict[str, Any], origin: str = "configuration") -> MissionConfig:
    """Checks a decoded configuration; the error names ``origin`` and the field."""
    try:
        config = MissionConfig.model_validate(raw)
    except ValidationError as error:
        raise ConfigError(f"{origin}: {describe_error(error)}") from None
    if config.robots.cell is not None:
        from bearchair.executive.cell_config import CellConfigError, parse_cell_config

        try:
            parse_cell_config(config.robots.cell, config.arena.arena())
        except CellConfigError as error:
            raise ConfigError(f"{origin}: robots.cell: {error}") from None
    return config


def with_overrides(config: MissionConfig, overrides: dict[str, Any]) -> MissionConfig:
    """``config`` with ``{"section.key": value}`` replaced, checked again.

    Raises:
        ConfigError: an override names no field or gives a wrong value (one line).
    """
    raw = config.model_dump(mode="json", exclude_none=True)
    for dotted, value in overrides.items():
        *sections, key = dotted.split(".")
        target = raw
        for section in sections:
            target = target.setdefault(section, {})
            if not isinstance(target, dict):
                raise ConfigError(f"--set {dotted}: {section} is not a section")
        target[key] = value
    return parse_mission_config(raw, "the command line")


def describe_error(error: ValidationError) -> str:
    """The first problem of a pydantic error as one line: ``field: what is wrong``."""
    first = error.errors()[0]
    location = ".".join(str(part) for part in first["loc"])
    more = error.error_count() - 1
    suffix = f" (and {more} more)" if more else ""
    if first["type"] == "extra_forbidden":
        return f"{location}: unknown key{_nearest(first['loc'])}{suffix}"
    message = first["msg"].removeprefix("Value error, ")
    if first["type"] == "value_error":  # our validators' messages name their field
        field, _, rest = message.partition(": ")
        if rest and " " not in field:
            location, message = f"{location}.{field}" if location else field, rest
        return f"{location or 'the file'}: {message}{suffix}"
    if "input" in first and first["type"] != "missing":
        got = repr(first["input"])
        message += f", got {got if len(got) <= 60 else got[:57] + '...'}"
    return f"{location or 'the file'}: {message}{suffix}"


def _nearest(location: tuple[Any, ...]) -> str:
    """`` (did you mean x?)`` for an unknown key, from the keys of its section."""
    model: type[BaseModel] | None = MissionConfig
    for part in location[:-1]:
        field = model.model_fields.get(str(part)) if model else None
        annotation = field.annotation if field else None
        model = (
            annotation
            if isinstance(annotation, type) and issubclass(annotation, BaseModel)
            else None
        )
    if model is None:
        return ""
    near = difflib.get_close_matches(str(location[-1]), list(model.model_fields), n=1, cutoff=0.5)
    return f" (did you mean {near[0]}?)" if near else f"; known: {', '.join(model.model_fields)}"


def _resolve_paths(raw: dict[str, Any], folder: Path) -> None:
    """Makes the input paths relative to the configuration file absolute."""
    for section, key in (("run", "chair"), ("robots", "cell_file")):
        table = raw.get(section)
        if isinstance(table, dict) and isinstance(table.get(key), str):
            path = Path(table[key]).expanduser()
            table[key] = str(path if path.is_absolute() else folder / path)
