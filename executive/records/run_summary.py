"""The run summary (``summary.json``) as typed, frozen records.

:class:`RunSummary` is built once at the end of a run (``bearchair.executive.runner.
summarise``), extended with :func:`dataclasses.replace` (the picture, the ground truth,
the recording's cost) and written by ``RunRecorder.write_summary``; everything that reads
a summary (``inspect``, the trials store, the worker, the benches) reads its attributes.

The file is the flat JSON object it always was, plus ``schema``
(:data:`SCHEMA_VERSION`). :meth:`RunSummary.from_json` reads a record of any earlier
version: a key it lacks takes the field's default, a key not of the record is ignored,
and a version-1 ``se2_goal`` (``x``, ``y``, ``theta`` in radians) is read in the units of
:meth:`bearchair.core.se2.SE2Pose.to_json`. A value of the wrong type is refused with
:class:`RunRecordError` naming the field.
"""

from __future__ import annotations

import math
import types
import typing
from collections.abc import Mapping
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, ClassVar, Literal, TypeVar

from bearchair.core.errors import RunRecordError

SCHEMA_VERSION = 2
"""The summary's version: 1 had no ``schema`` key and the goal's keys without units; 2
has the units in the goal's keys (2026-12-03)."""

Outcome = Literal["success", "failure"]

R = TypeVar("R", bound="JsonRecord")


class JsonRecord:
    """A frozen dataclass written as a JSON object, field by field, and read back checked.

    Fields in :attr:`OMITTED_WHEN_NONE` are left out of the JSON when None (keys the
    record has only sometimes: a signal, a picture).
    """

    OMITTED_WHEN_NONE: ClassVar[frozenset[str]] = frozenset()

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for item in fields(self):  # type: ignore[arg-type]  # every subclass is a dataclass
            value = getattr(self, item.name)
            if value is None and item.name in self.OMITTED_WHEN_NONE:
                continue
            out[item.name] = _to_json(value)
        return out

    @classmethod
    def from_json(cls: type[R], data: Mapping[str, Any]) -> R:
        """The record from its JSON object: missing keys take their defaults.

        Raises:
            RunRecordError: ``data`` is not an object, a value has the wrong type, or a
                key without a default is missing.
        """
        return _built(cls, _read_fields(cls, data))


@dataclass(frozen=True)
class RunInfo(JsonRecord):
    """What was run, where and when (the first keys of ``summary.json``).

    Attributes:
        chair: the chair's file name (``real`` on the robots).
        placement: how the simulated chair was placed (``real`` on the robots).
        helper: how the simulated helper reacted (``person`` on the robots).
        seed: the run's seed (None: a record that did not say).
        backend: ``sim`` or ``real``.
        tree: the tree that ran (``--tree``).
        started_at: local time the run started, ISO 8601.
        cell_file: on the robots, the cell file (or ``inline ([robots.cell])``).
        sdk_versions: on the robots, the SDKs' versions.
    """

    OMITTED_WHEN_NONE: ClassVar[frozenset[str]] = frozenset({"cell_file", "sdk_versions"})

    chair: str = ""
    placement: str = ""
    helper: str = ""
    seed: int | None = None
    backend: str = ""
    tree: str = "mission"
    started_at: str = ""
    cell_file: str | None = None
    sdk_versions: dict[str, Any] | None = None


@dataclass(frozen=True)
class StageRecord(JsonRecord):
    """One stage (a child of the tree's root) as the run left it.

    Attributes:
        name: the stage's name.
        status: its last py_trees status (``SUCCESS``, ``FAILURE``, ``RUNNING``, ``INVALID``).
        seconds: its wall seconds.
        robot_seconds: its seconds on the robot's clock (None: an old record).
        message: its deepest leaf's last feedback.
        robot_started_s: the robot's clock when it started (None: it never ran, or an old
            record); in simulation the simulated time the world's own records use.
    """

    name: str
    status: str = "INVALID"
    seconds: float = 0.0
    robot_seconds: float | None = None
    message: str = ""
    robot_started_s: float | None = None


@dataclass(frozen=True)
class SittingPoseRecord(JsonRecord):
    """The sitting pose the mission used (``SittingPose.to_json``), world frame.

    Attributes:
        position_m: the point p, metres.
        yaw_deg: the sitting direction γ, degrees.
    """

    position_m: tuple[float, ...]
    yaw_deg: float


@dataclass(frozen=True)
class JudgementRecord(JsonRecord):
    """The simulated judge's verdict on the seated bear (``SeatingJudgement``).

    Attributes:
        seated: every criterion held.
        on_seat: the bear touched the chair and not the floor.
        torso_tilt_deg: the torso's angle from vertical, degrees.
        facing_error_deg: the facing's angle from the true sitting direction, degrees.
        reason: which criterion failed (empty when seated).
        T_world_bear: the bear's 4x4 pose when judged (None: not known).
    """

    seated: bool
    on_seat: bool = False
    torso_tilt_deg: float | None = None
    facing_error_deg: float | None = None
    reason: str = ""
    T_world_bear: tuple[tuple[float, ...], ...] | None = None


@dataclass(frozen=True)
class ReleaseRecord(JsonRecord):
    """What the release imagination predicted for the planned release
    (``ReleasePrediction``'s JSON).

    Attributes:
        stays: the bear is predicted to stay seated.
        staying: imagined releases where it stays, ``k/n``.
        reason: why it falls where it does (most frequent first).
        released_at_m: where the bear is let go, world frame, metres.
        settled_at_m: where the planned release settles, world frame, metres.
        settled_yaw_deg: its settled yaw, degrees.
        settled_tilt_deg: its settled torso tilt, degrees.
        seconds: the imagination's wall seconds.
        cpu_seconds: its CPU seconds (None: an old record).
        seat_patched: the scan's seat was patched under the bear.
    """

    stays: bool
    staying: str = ""
    reason: str = ""
    released_at_m: tuple[float, ...] = ()
    settled_at_m: tuple[float, ...] = ()
    settled_yaw_deg: float | None = None
    settled_tilt_deg: float | None = None
    seconds: float = 0.0
    cpu_seconds: float | None = None
    seat_patched: bool = False


@dataclass(frozen=True)
class GroundTruth(JsonRecord):
    """What only the simulated world knows at the end of a run (the mission never sees it).

    Attributes:
        sitting_yaw_deg: the chair's true sitting direction, degrees (None: not known).
        sitting_yaw_error_deg: how far the mission's sitting direction was from it.
        nao_into_chair_cm: how deep the NAO went into the chair, centimetres.
        nao_into_chair_link: the NAO's link that went deepest ("" when none touched).
        nao_into_chair_stage: the stage running when it did ("" when none touched, or
            the run's record does not say).
        palms_apart_handed_over_cm: how far apart the NAO's palms were when they took
            the bear, centimetres (the carrying grip; 0: not measured).
        palms_apart_max_cm: the widest they were while holding it (the simulated bear is
            held by a constraint; a real one falls from palms wider than its torso).
        palms_apart_stage: the stage running when they were first that wide.
    """

    sitting_yaw_deg: float | None = None
    sitting_yaw_error_deg: float | None = None
    nao_into_chair_cm: float = 0.0
    nao_into_chair_link: str = ""
    nao_into_chair_stage: str = ""
    palms_apart_handed_over_cm: float = 0.0
    palms_apart_max_cm: float = 0.0
    palms_apart_stage: str = ""


@dataclass(frozen=True)
class RecordingCost(JsonRecord):
    """What a Rerun recording cost the run (``MissionRecording.cost``).

    Attributes:
        file: the recording's file name (None: streamed only).
        seconds: the recording hook's wall seconds.
        cpu_seconds: its CPU seconds.
        seconds_by_part: wall seconds of the five most expensive things logged.
    """

    file: str | None = None
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    seconds_by_part: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class RunSummary(JsonRecord):
    """How a run ended: ``summary.json``.

    Attributes:
        outcome: ``success`` or ``failure``.
        info: what was run (written as the first keys, not nested).
        failed_stage: the stage that failed (None on success, or when none started).
        reason: why the run failed (empty on success).
        interrupted: a stop signal ended it.
        signal: that signal's name.
        record_error: why the run record could not be written, when it could not.
        wall_seconds: the run's wall seconds.
        ticks: ticks of the tree.
        stages: the root's children, in order.
        sitting_pose: the sitting pose used (None: none imagined).
        se2_goal: the NAO's stance, ``SE2Pose.to_json`` (None: none planned).
        instructions: what the NAO asked the helper, in order.
        rotations: the chair's rotations asked for.
        measured_rotations: the registrations of the turned chair (their JSON).
        accessible: the last accessibility check's verdict.
        walk: the walk's result (its JSON).
        judgement: the simulated judge's verdict (None on the robots).
        release_prediction: the release imagination's prediction.
        failures: ``<leaf>: <feedback>`` of every leaf failure, in order.
        picture: the final scene's file name, when it was rendered.
        ground_truth: what only the simulated world knows.
        recording: the Rerun recording's cost, when recorded.
        software: the versions that wrote the record (``write_summary`` stamps them).
    """

    OMITTED_WHEN_NONE: ClassVar[frozenset[str]] = frozenset(
        {"signal", "record_error", "picture", "ground_truth", "recording", "software"}
    )

    outcome: Outcome
    info: RunInfo = field(default_factory=RunInfo)
    failed_stage: str | None = None
    reason: str = ""
    interrupted: bool = False
    signal: str | None = None
    record_error: str | None = None
    wall_seconds: float = 0.0
    ticks: int = 0
    stages: tuple[StageRecord, ...] = ()
    sitting_pose: SittingPoseRecord | None = None
    se2_goal: dict[str, float] | None = None
    instructions: tuple[str, ...] = ()
    rotations: int = 0
    measured_rotations: tuple[Any, ...] = ()
    accessible: bool = False
    walk: Any = None
    judgement: JudgementRecord | None = None
    release_prediction: ReleaseRecord | None = None
    failures: tuple[str, ...] = ()
    picture: str | None = None
    ground_truth: GroundTruth | None = None
    recording: RecordingCost | None = None
    software: dict[str, Any] | None = None

    @property
    def succeeded(self) -> bool:
        return self.outcome == "success"

    def stage(self, name: str) -> StageRecord | None:
        """The stage called ``name`` (None: the tree had none)."""
        return next((stage for stage in self.stages if stage.name == name), None)

    def stage_at(self, robot_time_s: float) -> str:
        """The stage that was running at ``robot_time_s`` on the robot's clock: the last to
        start at or before it ("" before the first, or in a record without start times).
        The stages are the root's children, which run one after another."""
        running, latest_start = "", -math.inf
        for stage in self.stages:
            start = stage.robot_started_s
            if start is not None and latest_start <= start <= robot_time_s:
                running, latest_start = stage.name, start
        return running

    def to_json(self) -> dict[str, Any]:
        """``summary.json``: ``schema``, the run's info, then the outcome's keys."""
        body = super().to_json()
        info = body.pop("info")
        return {"schema": SCHEMA_VERSION, **info, **body}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> RunSummary:
        """A summary of this or an earlier version (see the module docstring).

        Raises:
            RunRecordError: not an object, no ``outcome``, or a value of the wrong type.
        """
        if not isinstance(data, Mapping):
            raise RunRecordError("RunSummary: not a JSON object")
        if data.get("schema", 1) == 1:
            data = _from_version_1(data)
        values = _read_fields(cls, {key: value for key, value in data.items() if key != "info"})
        return _built(cls, {**values, "info": RunInfo.from_json(data)})


def _read_fields(cls: type[JsonRecord], data: Mapping[str, Any]) -> dict[str, Any]:
    """The values of ``cls``'s fields that ``data`` has, each checked against its type."""
    if not isinstance(data, Mapping):
        raise RunRecordError(f"{cls.__name__}: not a JSON object")
    hints = typing.get_type_hints(cls)
    return {
        item.name: _read(hints[item.name], data[item.name], f"{cls.__name__}.{item.name}")
        for item in fields(cls)  # type: ignore[arg-type]  # every subclass is a dataclass
        if item.name in data
    }


def _built(cls: type[R], values: dict[str, Any]) -> R:
    for item in fields(cls):  # type: ignore[arg-type]
        required = item.default is MISSING and item.default_factory is MISSING
        if required and item.name not in values:
            raise RunRecordError(f"{cls.__name__}: no {item.name!r}")
    return cls(**values)


def _from_version_1(data: Mapping[str, Any]) -> Mapping[str, Any]:
    """A version-1 summary's goal (``x``, ``y`` metres, ``theta`` radians) in version 2's
    keys, rounded as ``SE2Pose.to_json`` rounds."""
    goal = data.get("se2_goal")
    if not isinstance(goal, Mapping) or not {"x", "y", "theta"} <= set(goal):
        return data
    try:
        upgraded = {
            "x_m": round(float(goal["x"]), 4),
            "y_m": round(float(goal["y"]), 4),
            "theta_deg": round(math.degrees(float(goal["theta"])), 2),
        }
    except (TypeError, ValueError) as error:
        raise RunRecordError(f"summary: se2_goal: {error}") from error
    return {**data, "se2_goal": upgraded}


def _to_json(value: Any) -> Any:
    if isinstance(value, JsonRecord):
        return value.to_json()
    if isinstance(value, tuple | list):
        return [_to_json(item) for item in value]
    if isinstance(value, dict):
        return {key: _to_json(item) for key, item in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)  # as the blackboard's JSON view writes it (``to_jsonable``)
    return value


_NON_FINITE = frozenset({"nan", "inf", "-inf"})


def _read(hint: Any, value: Any, where: str) -> Any:
    """``value`` (JSON) as the field's type ``hint``; lists become tuples.

    Raises:
        RunRecordError: ``value`` is not of that type.
    """
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return value
    if origin in (types.UnionType, typing.Union):
        if value is None and type(None) in args:
            return None
        (inner,) = [arg for arg in args if arg is not type(None)]
        return _read(inner, value, where)
    if origin is Literal:
        if value in args:
            return value
    elif origin is tuple:
        if isinstance(value, list | tuple):
            return tuple(_read(args[0], item, f"{where}[{i}]") for i, item in enumerate(value))
    elif origin is dict:
        if isinstance(value, Mapping) and all(isinstance(key, str) for key in value):
            return {key: _read(args[1], item, f"{where}.{key}") for key, item in value.items()}
    elif isinstance(hint, type) and issubclass(hint, JsonRecord):
        if isinstance(value, Mapping):
            return hint.from_json(value)
    else:
        return _scalar(hint, value, where)
    raise RunRecordError(f"{where}: {_shown(value)} is not {_named(hint)}")


def _scalar(hint: type, value: Any, where: str) -> Any:
    if hint is float and isinstance(value, str) and value in _NON_FINITE:
        return float(value)
    if hint is float and isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    is_bool = isinstance(value, bool)
    if hint in (int, str, bool) and isinstance(value, hint) and (hint is bool) >= is_bool:
        return value  # a bool is an int to Python, never to a record
    raise RunRecordError(f"{where}: {_shown(value)} is not {_named(hint)}")


def _named(hint: Any) -> str:
    if typing.get_origin(hint) is Literal:
        return "one of " + ", ".join(repr(arg) for arg in typing.get_args(hint))
    return getattr(hint, "__name__", None) or str(hint).replace("typing.", "")


def _shown(value: Any) -> str:
    return repr(value)[:60]
