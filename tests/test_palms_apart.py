"""How far apart the NAO's palms hold the bear: the simulated world's monitor, the
ground truth it gives, and the campaign's report of it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bearchair.core.geometry import make_transform
from bearchair.core.nao_carrying import CARRYING_POSTURE_RAD, PALM_IN_WRIST_M
from bearchair.evaluation.ground_truth_report import palms_apart
from bearchair.evaluation.protocol import TrialSpec
from bearchair.evaluation.report import compute_table, format_table
from bearchair.evaluation.store import record_from_summary
from bearchair.executive.records.run_summary import RunSummary
from bearchair.hardware.sim.grip import PalmsApartMonitor
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.skills.planning.wholebody.nao_model import link_transforms


class _Hands:
    """A NAO whose palms are 2·half_m apart along y, and a bear it holds or not."""

    def __init__(self) -> None:
        self.half_m = 0.07
        self.posture_count = 0
        self.held = True

    def T_world_link(self, link_name: str) -> np.ndarray:
        side = {"l_wrist": 1.0, "r_wrist": -1.0}[link_name]
        wrist = np.array([0.1, side * self.half_m, 0.4]) - np.asarray(PALM_IN_WRIST_M)
        return make_transform(np.eye(3), wrist)

    def move(self, half_m: float) -> None:
        self.half_m = half_m
        self.posture_count += 1


def test_the_monitor_keeps_the_hand_over_and_the_widest_while_held():
    hands = _Hands()
    monitor = PalmsApartMonitor(hands, hands)
    monitor(0.5, 0.01)
    assert monitor.widest.handed_over_m == pytest.approx(0.14)
    hands.move(0.11)
    monitor(2.0, 0.01)
    hands.move(0.09)
    monitor(3.0, 0.01)
    assert monitor.widest.widest_m == pytest.approx(0.22) and monitor.widest.time_s == 2.0
    # Let go, the hands may open as wide as they like.
    hands.held = False
    hands.move(0.3)
    monitor(4.0, 0.01)
    assert monitor.widest.widest_m == pytest.approx(0.22)
    assert monitor.widest.handed_over_m == pytest.approx(0.14)


def test_the_simulated_nao_takes_the_bear_with_the_carrying_posture_s_palms():
    """The world's first measurement is the carrying grip, as the planner's kinematics
    put it (``core.nao_carrying``: the palms about 7 cm either side)."""
    transforms = link_transforms(CARRYING_POSTURE_RAD)
    palm = np.r_[PALM_IN_WRIST_M, 1.0]
    expected_m = float(
        np.linalg.norm((transforms["l_wrist"] @ palm)[:3] - (transforms["r_wrist"] @ palm)[:3])
    )
    with SimWorld(SimConfig(seed=0)) as world:
        world.clock.sleep(0.1)
        widest = world.palms_apart.widest
    assert widest.handed_over_m == pytest.approx(expected_m, abs=0.002)
    assert widest.widest_m == pytest.approx(widest.handed_over_m, abs=0.002)


def _record(index: int, handed_cm: float, widest_cm: float, stage: str):
    spec = TrialSpec("c.obj", Path("c.obj"), index, "accessible", "accessible", "obeys", index)
    summary = RunSummary.from_json(
        {
            "outcome": "success",
            "stages": [],
            "ground_truth": {
                "palms_apart_handed_over_cm": handed_cm,
                "palms_apart_max_cm": widest_cm,
                "palms_apart_stage": stage,
            },
        }
    )
    return record_from_summary(spec, summary, 30.0, None)


def test_the_report_counts_the_trials_whose_palms_held_the_bear_wider_than_they_took_it():
    records = [
        _record(0, 14.3, 14.3, ""),
        _record(1, 14.3, 15.0, "SeatBear"),
        _record(2, 14.3, 22.6, "SeatBear"),
        _record(3, 14.3, 22.4, "ReleaseAndStand"),
    ]
    palms = palms_apart(records)
    assert palms is not None
    assert (palms.trials, palms.wider) == (4, 2)
    assert palms.handed_over_cm == pytest.approx(14.3)
    assert palms.widest_max_cm == pytest.approx(22.6)
    assert palms.by_stage == (("ReleaseAndStand", 1), ("SeatBear", 1))
    assert "2 of 4 trials held it more than 1 cm wider" in format_table(compute_table(records))
    # Records without the measurement (older campaigns) leave it out.
    assert palms_apart([_record(0, 0.0, 0.0, "")]) is None
