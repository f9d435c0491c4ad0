"""What only the simulated world knows, over a campaign: how deep the NAO went into the
chairs and how far apart its palms held the bear (the run's ``ground_truth``, kept in the
trial records). The mission never reads it; the report and the benches do."""

from __future__ import annotations

import statistics
from collections import Counter
from typing import NamedTuple

from bearchair.core.userfiles import printable
from bearchair.evaluation.trial_record import TrialRecord

TOUCH_DEPTHS_CM = (1.0, 2.0, 5.0)
"""Depths (centimetres) beyond which the report counts the NAO's touches of the chair."""


class NaoIntoChair(NamedTuple):
    """Ground truth over the simulated trials: how deep the NAO went into the chair.

    In simulation the NAO is kinematic and the chair static, so the NAO passes through
    where a real one would push the chair, jam a hand or drop the bear.

    Attributes:
        trials: trials with the measurement.
        touched: trials in which the NAO touched the chair at all.
        deeper_than: (depth in cm, trials deeper) for each of :data:`TOUCH_DEPTHS_CM`.
        by_stage: (stage, trials) of the touches deeper than the first of those depths,
            most first.
        deepest: (chair, trial index, cm, link, stage) of the five deepest touches.
    """

    trials: int
    touched: int
    deeper_than: tuple[tuple[float, int], ...]
    by_stage: tuple[tuple[str, int], ...]
    deepest: tuple[tuple[str, int, float, str, str], ...]


PALMS_WIDER_CM = 1.0
"""The report counts the trials whose palms held the bear more than this much wider than
when they took it (centimetres): a real bear held between the palms is no longer squeezed."""


class HeldPalms(NamedTuple):
    """Ground truth over the simulated trials: how far apart the NAO's palms held the bear
    (the simulated bear is held by a constraint and cannot slip out; a real one can).

    Attributes:
        trials: trials with the measurement.
        handed_over_cm: the median distance between the palms when they took the bear.
        widest_median_cm, widest_max_cm: the widest they held it, median and max over
            the trials.
        wider: trials whose palms held it more than :data:`PALMS_WIDER_CM` wider than
            when they took it.
        by_stage: (stage, trials) of those, where they were first widest, most first.
    """

    trials: int
    handed_over_cm: float
    widest_median_cm: float
    widest_max_cm: float
    wider: int
    by_stage: tuple[tuple[str, int], ...]


def nao_into_chair(records: list[TrialRecord]) -> NaoIntoChair | None:
    """How deep the NAO went into the chair over ``records`` (None: none measured it)."""
    depths = [(r, r.nao_into_chair_cm) for r in records if r.nao_into_chair_cm is not None]
    if not depths:
        return None
    stages = Counter(
        r.nao_into_chair_stage or "unknown" for r, cm in depths if cm > TOUCH_DEPTHS_CM[0]
    )
    touched = sorted(((r, cm) for r, cm in depths if cm > 0.0), key=lambda pair: -pair[1])
    return NaoIntoChair(
        trials=len(depths),
        touched=len(touched),
        deeper_than=tuple(
            (limit, sum(cm > limit for _, cm in depths)) for limit in TOUCH_DEPTHS_CM
        ),
        by_stage=tuple(sorted(stages.items(), key=lambda item: (-item[1], item[0]))),
        deepest=tuple(
            (r.chair, r.trial_index, cm, r.nao_into_chair_link or "", r.nao_into_chair_stage or "")
            for r, cm in touched[:5]
        ),
    )


def palms_apart(records: list[TrialRecord]) -> HeldPalms | None:
    """How far apart the NAO's palms held the bear over ``records`` (None: none measured it)."""
    measured = [
        (r, r.palms_apart_handed_over_cm or 0.0, r.palms_apart_max_cm or 0.0)
        for r in records
        if r.palms_apart_handed_over_cm
    ]
    if not measured:
        return None
    wider = [r for r, handed, widest in measured if widest > handed + PALMS_WIDER_CM]
    stages = Counter(r.palms_apart_stage or "unknown" for r in wider)
    widest = [w for _, _, w in measured]
    return HeldPalms(
        trials=len(measured),
        handed_over_cm=statistics.median(h for _, h, _ in measured),
        widest_median_cm=statistics.median(widest),
        widest_max_cm=max(widest),
        wider=len(wider),
        by_stage=tuple(sorted(stages.items(), key=lambda item: (-item[1], item[0]))),
    )


def touch_lines(touches: NaoIntoChair) -> list[str]:
    """The NAO's touches of the chair in a few lines of text (the terminal's and the
    report's)."""
    deeper = ", ".join(f"{n} deeper than {cm:g} cm" for cm, n in touches.deeper_than)
    lines = [
        "The NAO in the chair (the simulation's ground truth; a real chair would be pushed)",
        f"  {touches.touched} of {touches.trials} trials touched it: {deeper}",
    ]
    if touches.by_stage:
        lines.append(
            f"  deeper than {TOUCH_DEPTHS_CM[0]:g} cm, by stage: "
            + ", ".join(f"{stage} {n}" for stage, n in touches.by_stage)
        )
    if touches.deepest:
        lines.append(
            "  deepest: "
            + "; ".join(
                f"{printable(chair)} #{index} {cm:.1f} cm ({link}{', ' + stage if stage else ''})"
                for chair, index, cm, link, stage in touches.deepest
            )
        )
    return lines


def palms_lines(palms: HeldPalms) -> list[str]:
    """How far apart the palms held the bear, in a few lines of text (the terminal's and
    the report's)."""
    lines = [
        "The NAO's palms holding the bear (ground truth; the simulated bear cannot slip out)",
        f"  taken {palms.handed_over_cm:.1f} cm apart; widest while held: median "
        f"{palms.widest_median_cm:.1f} cm, max {palms.widest_max_cm:.1f} cm",
        f"  {palms.wider} of {palms.trials} trials held it more than {PALMS_WIDER_CM:g} cm "
        "wider than they took it",
    ]
    if palms.by_stage:
        lines.append(
            "  first widest in: " + ", ".join(f"{stage} {n}" for stage, n in palms.by_stage)
        )
    return lines
