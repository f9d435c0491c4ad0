"""One finished trial as a typed, frozen record: a row of the campaign's SQLite records.

The table's columns are ``bearchair.evaluation.store.COLUMNS`` (one per field here); the
report, the pictures, the progress line and the benches read the fields. A row of an
older database lacks the columns added since: they read as None (the store adds them
empty).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from bearchair.core.errors import RunRecordError
from bearchair.executive.records.run_summary import SittingPoseRecord

BOOLEAN_COLUMNS = frozenset(
    {"accessible_final", "accessible_after_assistance", "seated", "on_seat"}
)
"""Columns SQLite keeps as 0/1."""


@dataclass(frozen=True)
class TrialRecord:
    """One finished trial (a summary, a crash or a timeout).

    Attributes:
        chair: the chair's file name.
        placement: ``accessible`` or ``inaccessible``.
        helper: ``obeys`` or ``disobeys``.
        trial_index: the trial's index for this chair.
        seed: the trial's seed.
        experiment: the protocol's experiment.
        outcome: ``success`` or ``failure``.
        chair_path: the mesh file.
        failed_stage: the stage that failed (None: none, or a crash).
        reason: why it failed (the crash's error when it did not end).
        rotations: rotations asked of the helper (None: no summary).
        instructions: sentences said (None: no summary).
        accessible_final: the last accessibility check said accessible.
        accessible_after_assistance: as above, only when an instruction was given.
        stage_seconds: stage name -> wall seconds, of the stages that ran.
        seated: the judge's verdict (None: not judged).
        on_seat: the bear touched the chair and not the floor.
        torso_tilt_deg: the bear's torso from vertical, degrees.
        facing_error_deg: the bear's facing from the true front, degrees.
        judgement_reason: which of the judge's criteria failed.
        sitting_pose: the sitting pose at the end of the trial, world frame.
        mission_seconds: the mission's own wall seconds (the summary's ``wall_seconds``).
        wall_seconds: the whole trial subprocess's, world building included.
        error: crash, timeout or worker error; None when the mission ran to its end.
        attempts: worker runs (2 when a crashed or killed worker was retried).
        run_dir: the trial's run record.
        finished_at: local time it was recorded, ISO 8601.
        software: the versions that ran it.
        nao_into_chair_cm: ground truth: how deep the NAO went into the chair, centimetres
            (None: not simulated, or no summary).
        nao_into_chair_link: the NAO's link that went deepest ("" when none touched).
        nao_into_chair_stage: the stage running when it did.
        palms_apart_handed_over_cm: ground truth: how far apart the NAO's palms took the
            bear, centimetres (None: not simulated, no summary, or an older record).
        palms_apart_max_cm: the widest they held it.
        palms_apart_stage: the stage running when they were first that wide.
    """

    chair: str
    placement: str
    helper: str
    trial_index: int
    seed: int
    experiment: str
    outcome: str
    chair_path: str | None = None
    failed_stage: str | None = None
    reason: str | None = None
    rotations: int | None = None
    instructions: int | None = None
    accessible_final: bool | None = None
    accessible_after_assistance: bool | None = None
    stage_seconds: dict[str, float] = field(default_factory=dict)
    seated: bool | None = None
    on_seat: bool | None = None
    torso_tilt_deg: float | None = None
    facing_error_deg: float | None = None
    judgement_reason: str | None = None
    sitting_pose: SittingPoseRecord | None = None
    mission_seconds: float | None = None
    wall_seconds: float | None = None
    error: str | None = None
    attempts: int | None = None
    run_dir: str | None = None
    finished_at: str | None = None
    software: dict[str, Any] | None = None
    nao_into_chair_cm: float | None = None
    nao_into_chair_link: str | None = None
    nao_into_chair_stage: str | None = None
    palms_apart_handed_over_cm: float | None = None
    palms_apart_max_cm: float | None = None
    palms_apart_stage: str | None = None

    @property
    def succeeded(self) -> bool:
        return self.outcome == "success"

    @property
    def key(self) -> tuple[str, str, str, int, int]:
        """What identifies the trial (``TrialSpec.key``)."""
        return (self.chair, self.placement, self.helper, self.trial_index, self.seed)

    def to_row(self) -> dict[str, Any]:
        """Column -> value, JSON columns as Python values (the store encodes them)."""
        row = {item.name: getattr(self, item.name) for item in fields(self)}
        if self.sitting_pose is not None:
            row["sitting_pose"] = self.sitting_pose.to_json()
        return row

    @classmethod
    def from_row(cls, row: Mapping[str, Any]) -> TrialRecord:
        """A record from a row (JSON columns decoded; a column it lacks reads as None).

        A sitting pose that is not one (a damaged row) reads as None.
        """
        names = {item.name for item in fields(cls)}
        values = {key: value for key, value in row.items() if key in names}
        for name in BOOLEAN_COLUMNS & set(values):
            values[name] = None if values[name] is None else bool(values[name])
        values["stage_seconds"] = dict(values.get("stage_seconds") or {})
        values["sitting_pose"] = _sitting_pose(values.get("sitting_pose"))
        return cls(**values)


def _sitting_pose(value: Any) -> SittingPoseRecord | None:
    if value is None or isinstance(value, SittingPoseRecord):
        return value
    try:
        return SittingPoseRecord.from_json(value)
    except RunRecordError:
        return None
