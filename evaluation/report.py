"""The campaign's summary, computed from the records alone: the paper's Table 1 and more.

Table 1 of the paper has two parts. (1) Seating bear success by experiment: trials and
successes. (2) Chair accessible after human assistance, over the trials in which an
instruction was given (the paper disregards trials where imagination failed and no
instruction was said). Here a trial is a success when the simulated judge says the bear
is seated, and the chair is accessible after assistance when the mission's last
accessibility check said so. Added: the median time of each stage and the causes of
failure.
"""

from __future__ import annotations

import re
import statistics
from collections import Counter
from pathlib import Path
from typing import Any, NamedTuple
from urllib.parse import quote

from bearchair.behaviours.accessibility import REFUSED
from bearchair.core.userfiles import printable
from bearchair.evaluation.ground_truth_report import (
    TOUCH_DEPTHS_CM,
    HeldPalms,
    NaoIntoChair,
    nao_into_chair,
    palms_apart,
    palms_lines,
    touch_lines,
)
from bearchair.evaluation.pictures import trial_picture_name
from bearchair.evaluation.protocol import EXPERIMENT_LABELS, EXPERIMENTS, SkippedChair
from bearchair.evaluation.trial_record import TrialRecord
from bearchair.trees.mission import STAGES


class RateRow(NamedTuple):
    """One row of a table: a count out of a number of trials."""

    label: str
    n: int
    count: int

    @property
    def rate(self) -> float | None:
        return self.count / self.n if self.n else None


class TrialsTable(NamedTuple):
    """The paper's Table 1 from the records.

    Attributes:
        seating: (1) rows Accessible, Inaccessible + Human Obeys, ... , Total: trials, successes.
        assistance: (2) rows Obeys, Disobeys, Total: trials with an instruction, accessible after.
        stage_median_s: stage name -> (median seconds, trials where it ran).
        trial_median_s: median wall time of a whole trial (its subprocess), if any.
        failure_stages: (failed stage, count), most frequent first ("harness" for crashes
            and timeouts).
        failure_kinds: (cause with its numbers replaced by "#", count), most frequent
            first: the same kind of failure with different measurements counts together.
        failure_causes: (cause, count), most frequent first.
        errors: trials that crashed or hung.
        assisted_accessible_trials: accessible placements that were nevertheless assisted.
        refusals: (chair, the refusal's reason, trials) for chairs whose seat no stance
            reaches: refused right after imagination, a cause of their own.
        nao_into_chair: the NAO's touches of the chair (None: no trial measured them).
        palms_apart: how far apart the palms held the bear (None: no trial measured it).
    """

    seating: list[RateRow]
    assistance: list[RateRow]
    stage_median_s: dict[str, tuple[float, int]]
    trial_median_s: float | None
    failure_stages: list[tuple[str, int]]
    failure_kinds: list[tuple[str, int]]
    failure_causes: list[tuple[str, int]]
    errors: int
    assisted_accessible_trials: int
    refusals: tuple[tuple[str, str, int], ...] = ()
    nao_into_chair: NaoIntoChair | None = None
    palms_apart: HeldPalms | None = None


def compute_table(records: list[TrialRecord]) -> TrialsTable:
    """Table 1, stage medians and failure causes from records of ``bearchair.evaluation.store``."""
    seating = []
    for experiment in EXPERIMENTS:
        rows = [r for r in records if r.experiment == experiment]
        successes = sum(r.succeeded for r in rows)
        seating.append(RateRow(EXPERIMENT_LABELS[experiment], len(rows), successes))
    seating.append(RateRow("Total", len(records), sum(r.succeeded for r in records)))

    assistance = []
    for experiment, label in (
        ("inaccessible_obeys", "Obeys"),
        ("inaccessible_disobeys", "Disobeys"),
    ):
        assisted = [r for r in records if r.experiment == experiment and (r.instructions or 0) > 0]
        accessible = sum(bool(r.accessible_after_assistance) for r in assisted)
        assistance.append(RateRow(label, len(assisted), accessible))
    assistance.append(
        RateRow("Total", sum(r.n for r in assistance), sum(r.count for r in assistance))
    )

    durations: dict[str, list[float]] = {}
    for record in records:
        for stage, seconds in record.stage_seconds.items():
            durations.setdefault(stage, []).append(float(seconds))
    ordered = [s for s in STAGES if s in durations] + sorted(
        s for s in durations if s not in STAGES
    )
    stage_median_s = {
        stage: (statistics.median(durations[stage]), len(durations[stage])) for stage in ordered
    }
    walls = [r.wall_seconds for r in records if r.wall_seconds is not None]

    failed = [r for r in records if not r.succeeded]
    causes = Counter(failure_cause(r) for r in failed)
    stages = Counter(failure_cause(r).split(":", 1)[0] for r in failed)
    kinds = Counter(failure_kind(failure_cause(r)) for r in failed)
    return TrialsTable(
        seating=seating,
        assistance=assistance,
        stage_median_s=stage_median_s,
        trial_median_s=statistics.median(walls) if walls else None,
        failure_stages=sorted(stages.items(), key=lambda item: (-item[1], item[0])),
        failure_kinds=sorted(kinds.items(), key=lambda item: (-item[1], item[0])),
        failure_causes=sorted(causes.items(), key=lambda item: (-item[1], item[0])),
        errors=sum(bool(r.error) for r in records),
        assisted_accessible_trials=sum(
            r.experiment == "accessible" and (r.instructions or 0) > 0 for r in records
        ),
        refusals=_refusals(failed),
        nao_into_chair=nao_into_chair(records),
        palms_apart=palms_apart(records),
    )


def _refusals(failed: list[TrialRecord]) -> tuple[tuple[str, str, int], ...]:
    """(chair, reason, trials) of the refused trials, by chair (see :func:`refusal`)."""
    by_chair: dict[str, list[str]] = {}
    for record in failed:
        reason = refusal(record)
        if reason:
            by_chair.setdefault(record.chair, []).append(reason)
    return tuple(
        (chair, Counter(reasons).most_common(1)[0][0], len(reasons))
        for chair, reasons in sorted(by_chair.items())
    )


def refusal(record: TrialRecord) -> str:
    """Why the mission refused the chair (``CheckSeatReachable``, or ``NoSittingFound``
    where no sitting was imagined: a message starting with ``refused: ``), empty when it
    did not (it succeeded, or failed otherwise: say, a scan that cannot tell)."""
    if record.succeeded or not record.failed_stage:
        return ""
    message = failure_cause(record).split(": ", 1)[1]
    # The stage's own leaf writes its message bare; a leaf inside it prefixes its name.
    for text in (message, message.split(": ", 1)[-1]):
        if text.startswith(REFUSED):
            return text.removeprefix(REFUSED)
    return ""


def failure_kind(cause: str) -> str:
    """The cause with every number replaced by ``#`` ("torso tilted # deg > #")."""
    return re.sub(r"-?\d+(\.\d+)?", "#", cause)


def failure_cause(record: TrialRecord) -> str:
    """``failed_stage: reason`` (the reason without its leaf prefix), or the crash error."""
    if record.error and not record.failed_stage:
        return f"harness: {record.error}"
    stage = record.failed_stage or "unknown stage"
    reason = (record.reason or "").strip()
    # summarise() writes "<leaf name>: <message>": the leaf is often the stage itself.
    if reason.startswith(f"{stage}: "):
        reason = reason[len(stage) + 2 :]
    return f"{stage}: {reason or 'no reason given'}"


def _rate(row: RateRow) -> str:
    return "-" if row.rate is None else f"{100.0 * row.rate:.1f}%"


def format_table(table: TrialsTable) -> str:
    """Table 1 and the extras as plain text for the terminal."""
    width = max(len(row.label) for row in table.seating) + 2
    lines = [
        "(1) Seating bear success",
        f"{'Experiment':<{width}}{'Trials':>7}{'Success':>9}{'Rate':>8}",
    ]
    for row in table.seating:
        lines.append(f"{row.label:<{width}}{row.n:>7}{row.count:>9}{_rate(row):>8}")
    lines += ["", "(2) Chair accessible after human assistance"]
    lines.append(f"{'Helper':<{width}}{'Assist.':>7}{'Access.':>9}{'Rate':>8}")
    for row in table.assistance:
        lines.append(f"{row.label:<{width}}{row.n:>7}{row.count:>9}{_rate(row):>8}")
    if table.assisted_accessible_trials:
        lines.append(
            f"(and {table.assisted_accessible_trials} accessible placement(s) judged inaccessible "
            "and assisted)"
        )
    lines += ["", "Median time per stage"]
    for stage, (median, n) in table.stage_median_s.items():
        lines.append(f"  {stage:<22}{median:>8.1f} s  (n={n})")
    if table.trial_median_s is not None:
        lines.append(f"  {'whole trial (wall)':<22}{table.trial_median_s:>8.1f} s")
    if table.refusals:
        trials = sum(n for _, _, n in table.refusals)
        lines += [
            "",
            f"Refused (no stance reaches the seat): {trials} trial(s) on "
            f"{len(table.refusals)} chair(s)",
        ]
        lines += [
            f"  {printable(chair)} ({n}): {printable(reason)}"
            for chair, reason, n in table.refusals
        ]
    if table.nao_into_chair is not None:
        lines += ["", *touch_lines(table.nao_into_chair)]
    if table.palms_apart is not None:
        lines += ["", *palms_lines(table.palms_apart)]
    lines += ["", "Causes of failure"]
    if not table.failure_causes:
        lines.append("  none")
    else:
        lines.append("  by stage: " + ", ".join(f"{s} {n}" for s, n in table.failure_stages))
    for kind, count in table.failure_kinds:
        lines.append(f"  {count:>3} x {printable(kind)}")
    if table.failure_causes:
        lines.append("  (every cause with its numbers: report.md)")
    return "\n".join(lines)


def markdown_report(
    table: TrialsTable,
    records: list[TrialRecord],
    skipped: list[SkippedChair] | None = None,
    title: str = "Trials",
    settings: dict[str, Any] | None = None,
    chair_pictures: dict[str, str] | None = None,
    seat_heights_m: dict[str, float] | None = None,
) -> str:
    """The campaign report in Markdown: Table 1, stage medians, failures, every trial.

    ``seat_heights_m`` (chair -> the manifest's seat height, where it gives one) puts the
    true seat height beside each refusal, to read it against the reach model.
    """
    out = [f"# {title}", ""]
    if settings:
        out += [", ".join(f"{k}: {_md(v)}" for k, v in settings.items()), ""]
    out += _md_table_1(table)
    out += _md_stage_medians(table, len(records))
    out += _md_failures(table, seat_heights_m or {})
    if table.nao_into_chair is not None:
        out += _md_touches(table.nao_into_chair)
    if table.palms_apart is not None:
        out += ["", "## The NAO's palms holding the bear (ground truth)", ""]
        out += [_md(line.strip()) + "  " for line in palms_lines(table.palms_apart)[1:]]
    if skipped:
        out += ["", "## Meshes not in the campaign", ""]
        out += [f"- {_md(s.name)}: {_md(s.reason)}" for s in skipped]
    out += _md_trials(records)
    if chair_pictures:
        out += ["", "## Imagined sitting poses", ""]
        out += [f"![{_md(chair)}]({_link(path)})" for chair, path in sorted(chair_pictures.items())]
    return "\n".join(out) + "\n"


def _md_rate_table(title: str, columns: tuple[str, str, str], rows: Any) -> list[str]:
    """A section of Table 1: its title and one row per condition (count of n, and rate)."""
    out = [f"## {title}", "", f"| {' | '.join(columns)} | Rate |", "|---|---:|---:|---:|"]
    return out + [f"| {r.label} | {r.n} | {r.count} | {_rate(r)} |" for r in rows]


def _md_table_1(table: TrialsTable) -> list[str]:
    """The report's lines of Table 1: (1) seating success, (2) accessible after assistance."""
    out = _md_rate_table(
        "(1) Seating bear success", ("Experiment", "Trial num.", "Successes"), table.seating
    )
    out += [""]
    out += _md_rate_table(
        "(2) Chair accessible after human assistance",
        ("Helper (inaccessible placements)", "Assist. num.", "Accessible num."),
        table.assistance,
    )
    out += [
        "",
        "Assist. num. counts the trials in which at least one instruction was given; a chair "
        "is accessible after assistance when the mission's last accessibility check said so.",
    ]
    if table.assisted_accessible_trials:
        out.append(
            f"{table.assisted_accessible_trials} accessible placement(s) were judged "
            "inaccessible and assisted (not counted above)."
        )
    return out


def _md_stage_medians(table: TrialsTable, trials: int) -> list[str]:
    """The report's lines of the median stage times, the whole trial's among them."""
    out = [
        "",
        "## Median time per stage",
        "",
        "| Stage | Median (s) | Trials |",
        "|---|---:|---:|",
    ]
    out += [f"| {s} | {m:.1f} | {n} |" for s, (m, n) in table.stage_median_s.items()]
    if table.trial_median_s is not None:
        out.append(f"| whole trial (wall) | {table.trial_median_s:.1f} | {trials} |")
    return out


def _md_failures(table: TrialsTable, seat_heights_m: dict[str, float]) -> list[str]:
    """The report's lines of the refused chairs and the causes of failure."""
    out: list[str] = []
    if table.refusals:
        out += ["", "## Refused chairs (no stance reaches the seat)", ""]
        for chair, reason, n in table.refusals:
            seat = seat_heights_m.get(chair)
            known = f", manifest seat {seat:.3f} m" if seat is not None else ""
            out.append(f"- {_md(chair)} ({n} trials{known}): {_md(reason)}")
    out += ["", "## Causes of failure", ""]
    if not table.failure_causes:
        out.append("None.")
    else:
        out += ["| Failed stage | Trials |", "|---|---:|"]
        out += [f"| {_md(s)} | {n} |" for s, n in table.failure_stages]
        out.append("")
    if table.failure_kinds:
        out += ["By kind (numbers replaced by #):", ""]
        out += [f"- {count} x {_md(kind)}" for kind, count in table.failure_kinds]
        out += ["", "Every cause:", ""]
    out += [f"- {count} x {_md(cause)}" for cause, count in table.failure_causes]
    return out


def _md_touches(touches: NaoIntoChair) -> list[str]:
    """The report's lines of how deep the NAO went into the chairs."""
    out = [
        "",
        "## The NAO in the chair (ground truth)",
        "",
        "The simulated NAO passes through the chair where a real one would push it, jam a hand "
        f"or drop the bear. {touches.touched} of {touches.trials} trials touched the chair.",
        "",
        "| Deeper than | Trials |",
        "|---:|---:|",
    ]
    out += [f"| {cm:g} cm | {n} |" for cm, n in touches.deeper_than]
    if touches.by_stage:
        out += ["", f"Deeper than {TOUCH_DEPTHS_CM[0]:g} cm, by stage:", ""]
        out += [f"- {_md(stage)}: {n}" for stage, n in touches.by_stage]
    if touches.deepest:
        out += ["", "The deepest:", ""]
        out += [
            f"- {_md(chair)} #{index}: {cm:.1f} cm, {_md(link)}"
            + (f" during {_md(stage)}" if stage else "")
            for chair, index, cm, link, stage in touches.deepest
        ]
    return out


def _md_trials(records: list[TrialRecord]) -> list[str]:
    """The report's table of every trial, with a link to its final scene when there is one."""
    out = [
        "",
        "## Trials",
        "",
        "| Chair | # | Experiment | Seed | Outcome | Failed stage | Rotations | Accessible after | "
        "Facing err. (deg) | Wall (s) | Scene |",
        "|---|---:|---|---:|---|---|---:|---|---:|---:|---|",
    ]
    for r in records:
        scene = Path(r.run_dir or "") / "final_scene.png"
        picture = (
            f"[png]({_link('trials/' + trial_picture_name(r))})"
            if r.run_dir and scene.is_file()
            else ""
        )
        facing = r.facing_error_deg
        after = r.accessible_after_assistance
        out.append(
            f"| {_md(r.chair)} | {r.trial_index} | {_md(r.experiment)} | {r.seed} | "
            f"{_md(r.outcome)} | {_md(r.failed_stage or ('error' if r.error else ''))} | "
            f"{'' if r.rotations is None else r.rotations} | "
            f"{'' if after is None else ('yes' if after else 'no')} | "
            f"{'' if facing is None else f'{facing:.1f}'} | {r.wall_seconds or 0:.1f} | "
            f"{picture} |"
        )
    return out


def _md(text: object) -> str:
    """``text`` safe inside a Markdown table cell or list item, and as HTML: no control
    character, no live tag (``<img onerror=...>`` stays text), no ``|`` splitting a row,
    no ``[`` or ``]`` closing a link's text."""
    shown = printable(str(text).replace("\n", " "), 400)
    shown = shown.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    for special in ("\\", "|", "[", "]"):
        shown = shown.replace(special, "\\" + special)
    return shown


def _link(path: str) -> str:
    """A relative link target: each character outside a plain file name percent-quoted."""
    return quote(path, safe="/._-")
