"""The release imagination: the bear model let go over a chair, judged by the judge's rules."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bearchair.core.geometry import SittingPose, make_transform
from bearchair.core.meshes import box_chair_mesh
from bearchair.core.nao_carrying import PLACEMENT_TOLERANCE_M
from bearchair.core.se2 import SE2Pose
from bearchair.hardware.seating_criteria import judge_bear_pose
from bearchair.skills.imagination.release import imagine_release, perturbations
from bearchair.skills.planning.wholebody import InfeasibleSeating, release_choice
from bearchair.skills.planning.wholebody.seating import plan_seating

SEAT_HEIGHT_M = 0.24
SITTING_POSE = SittingPose(np.array([0.02, 0.0, SEAT_HEIGHT_M + 0.02]), 0.0)
NAO_POSE = SE2Pose(0.32, 0.0, math.pi)


@pytest.fixture(scope="module")
def chair():
    return box_chair_mesh(seat_height_m=SEAT_HEIGHT_M)


def _bear_at(x: float, z: float, lean_rad: float = 0.0) -> np.ndarray:
    """The bear facing +x (the box chair's front) at (x, 0, z), its top leaning back."""
    c, s = math.cos(-lean_rad), math.sin(-lean_rad)
    rot_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return make_transform(rot_y, np.array([x, 0.0, z]))


def test_a_bear_let_go_over_the_seat_stays_and_one_past_its_front_falls(chair):
    seat = imagine_release(chair, _bear_at(0.02, SEAT_HEIGHT_M + 0.01), 0.0, NAO_POSE)
    assert seat.stays and seat.staying == len(seat.releases) >= 3
    settled = np.asarray(seat.releases[0].judgement.T_world_bear)
    assert abs(settled[2, 3] - SEAT_HEIGHT_M) < 0.005  # resting on the seat's top
    past_front = imagine_release(chair, _bear_at(0.19, SEAT_HEIGHT_M + 0.01), 0.0, NAO_POSE)
    assert not past_front.stays and "floor" in past_front.reason
    assert past_front.to_json()["stays"] is False


def test_the_prediction_judges_the_facing_as_the_judge_does(chair):
    turned = imagine_release(chair, _bear_at(0.02, SEAT_HEIGHT_M + 0.01), math.pi / 2, NAO_POSE)
    assert not turned.stays and "facing off by 90 deg" in turned.reason


def test_the_judges_rules_on_a_bear_pose():
    upright = judge_bear_pose(_bear_at(0.0, 0.3), [np.array([0.0, 0.0, 0.3])], False, 0.0)
    assert upright.seated
    tipped = judge_bear_pose(_bear_at(0.0, 0.3, math.radians(40)), [np.zeros(3)], False, 0.0)
    assert not tipped.seated and "tilted 40 deg > 30" in tipped.reason
    # Reclined 40 deg against a backrest touching its upper torso: seated.
    reclined = _bear_at(0.0, 0.3, math.radians(40))
    back = reclined[:3, 3] + 0.13 * reclined[:3, 2]
    assert judge_bear_pose(reclined, [back], False, 0.0).seated
    assert not judge_bear_pose(_bear_at(0.0, 0.3), [], False, 0.0).seated


def test_perturbations_cover_the_walks_stop_box_and_the_seat_height():
    labels = [label for label, _ in perturbations(0.005, math.radians(2.5))]
    assert labels[0] == "as planned" and len(labels) == 6
    offsets = np.array([T[:3, 3] for _, T in perturbations(0.005, math.radians(2.5))])
    assert np.max(np.abs(offsets[:, :2])) == pytest.approx(0.005)
    assert offsets[:, 2].max() > 0.0


def test_the_planned_release_is_where_the_goal_holds_the_bear(chair):
    plan = plan_seating(chair, SITTING_POSE, NAO_POSE)
    T = release_choice.planned_release_pose(plan, NAO_POSE)
    assert abs(T[0, 3] - SITTING_POSE.position[0]) <= PLACEMENT_TOLERANCE_M + 1e-6
    assert 0.0 < T[2, 3] - SEAT_HEIGHT_M <= 0.0105  # let go at most 1 cm over the seat
    assert T[0, 0] > 0.99  # facing the NAO, i.e. the sitting direction
    assert T[0, 2] < 0.0  # its top leaning back, away from the NAO


@pytest.mark.slow
def test_no_placement_where_the_bear_stays_fails_before_the_release(chair, monkeypatch):
    falls = imagine_release(chair, _bear_at(0.19, SEAT_HEIGHT_M + 0.01), 0.0, NAO_POSE)
    tried = []

    def always_falls(*args, **kwargs):
        tried.append(args[1])
        return falls

    monkeypatch.setattr(release_choice, "predict_release", always_falls)
    monkeypatch.setenv(release_choice.RELEASE_CHECK_ENV, "choose")
    with pytest.raises(InfeasibleSeating, match="would not stay seated: the bear touches"):
        release_choice.plan_seating_released(chair, SITTING_POSE, NAO_POSE)
    assert len(tried) > 1  # other placements along the ray were tried
    for mode in ("predict", "prefer"):  # a prediction of "falls" alone releases as planned
        tried.clear()
        monkeypatch.setenv(release_choice.RELEASE_CHECK_ENV, mode)
        plan = release_choice.plan_seating_released(chair, SITTING_POSE, NAO_POSE)
        assert plan.release is falls and plan.to_json()["release"]["stays"] is False
        assert (len(tried) > 1) == (mode == "prefer")
    monkeypatch.setenv(release_choice.RELEASE_CHECK_ENV, "sometimes")
    with pytest.raises(ValueError, match="BEARCHAIR_RELEASE_CHECK"):
        release_choice.plan_seating_released(chair, SITTING_POSE, NAO_POSE)
    monkeypatch.delenv(release_choice.RELEASE_CHECK_ENV)
    assert release_choice.release_check_mode() == "prefer"  # the default


def test_a_seat_the_scan_lost_under_the_bear_is_taken_from_the_seat_map():
    import trimesh

    # A seat with a 0.10 x 0.12 m hole in its middle (what a scan that thinned out the
    # seat there shows), the bear's 0.085 x 0.10 m footprint over it.
    parts = [
        trimesh.creation.box((w, d, 0.02), trimesh.transformations.translation_matrix(c))
        for w, d, c in [
            (0.4, 0.14, (0.0, 0.13, 0.23)),
            (0.4, 0.14, (0.0, -0.13, 0.23)),
            (0.15, 0.12, (0.125, 0.0, 0.23)),
            (0.15, 0.12, (-0.125, 0.0, 0.23)),
        ]
    ]
    holed = trimesh.util.concatenate(parts)
    bear = _bear_at(0.0, SEAT_HEIGHT_M + 0.01)
    lost = imagine_release(holed, bear, 0.0, NAO_POSE)
    assert not lost.stays and not lost.seat_patched
    mapped = imagine_release(holed, bear, 0.0, NAO_POSE, seat_top_z=SEAT_HEIGHT_M)
    assert mapped.stays and mapped.seat_patched
    # Where the scan has the seat, nothing is added.
    solid_chair = box_chair_mesh(seat_height_m=SEAT_HEIGHT_M)
    solid = imagine_release(solid_chair, bear, 0.0, NAO_POSE, seat_top_z=SEAT_HEIGHT_M)
    assert solid.stays and not solid.seat_patched


def test_a_footprint_past_the_seats_edge_is_not_patched():
    # The box chair's seat ends at x = 0.14 m; the footprint's front reaches 0.1625 m.
    # Nothing is seen beyond its front corners: that is the seat's edge, not a hole.
    chair = box_chair_mesh(seat_height_m=SEAT_HEIGHT_M)
    over_edge = _bear_at(0.12, SEAT_HEIGHT_M + 0.01)
    edge = imagine_release(chair, over_edge, 0.0, NAO_POSE, seat_top_z=SEAT_HEIGHT_M)
    assert not edge.seat_patched


def test_the_runtime_reset_closes_every_release_world():
    # An open release world changed how another pybullet client's chair tipped
    # (test_imagination's support-hull test, after any release test): it is process state.
    from bearchair.core.meshes import box_chair_mesh
    from bearchair.core.runtime import RUNTIME
    from bearchair.skills.imagination import release

    world = release._world(box_chair_mesh())
    assert "release worlds" in RUNTIME.names()
    RUNTIME.reset()
    assert world.closed
    assert release._world(box_chair_mesh()) is not world


@pytest.mark.slow
def test_prefer_moves_p_to_the_first_other_placement_predicted_to_stay(chair, monkeypatch):
    falls = imagine_release(chair, _bear_at(0.19, SEAT_HEIGHT_M + 0.01), 0.0, NAO_POSE)
    stays = imagine_release(chair, _bear_at(0.0, SEAT_HEIGHT_M + 0.01), 0.0, NAO_POSE)
    assert stays.stays and not falls.stays
    tried: list[float] = []

    patched = stays._replace(seat_patched=True)

    def stays_only_nearer(chair_mesh, sitting_pose, humanoid_pose, plan):
        along_m = float(sitting_pose.position[0] - SITTING_POSE.position[0])
        tried.append(along_m)
        if along_m < -1e-9:  # deeper: stays only on a seat patched from the seat map
            return patched
        return stays if along_m > 0.0 else falls  # +x: toward the NAO

    monkeypatch.setattr(release_choice, "predict_release", stays_only_nearer)
    monkeypatch.setenv(release_choice.RELEASE_CHECK_ENV, "prefer")
    plan = release_choice.plan_seating_released(chair, SITTING_POSE, NAO_POSE)
    # As planned (falls), deeper (stays on a patched seat: not trusted), nearer (stays).
    assert plan.release is stays
    assert tried == pytest.approx([0.0, -0.02, 0.02])

    # A planned release whose bears all tipped over on the scanned seat (not through it
    # onto the floor) is outweighed by a "stays" on a patched seat: deeper is taken.
    tipped = falls._replace(
        releases=tuple(
            r._replace(judgement=r.judgement._replace(on_seat=True)) for r in falls.releases
        )
    )
    assert tipped.tipped_on_seat and not falls.tipped_on_seat and not stays.tipped_on_seat
    tried.clear()

    def tipped_as_planned(chair_mesh, sitting_pose, humanoid_pose, plan):
        along_m = float(sitting_pose.position[0] - SITTING_POSE.position[0])
        tried.append(along_m)
        return patched if along_m < -1e-9 else tipped

    monkeypatch.setattr(release_choice, "predict_release", tipped_as_planned)
    plan = release_choice.plan_seating_released(chair, SITTING_POSE, NAO_POSE)
    assert plan.release is patched
    assert tried == pytest.approx([0.0, -0.02])
