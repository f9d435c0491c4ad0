"""The parameters of the chair's registration after a helper's turn
(:func:`bearchair.skills.perception.registration.register_chair`) and of the visible
overlap that judges it (:mod:`bearchair.skills.perception.visible_overlap`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RegistrationConfig:
    """Parameters of :func:`register_chair` (metres, degrees).

    Attributes:
        hypothesis_step_deg: spacing of the initial yaw hypotheses.
        coarse_voxel_m, fine_voxel_m: downsampling of the coarse and fine ICP stages.
        coarse_distance_m, fine_distance_m: correspondence distances of the two stages.
        inlier_distance_m: a point within this of the reference after the fit is an inlier.
        min_fitness: reject when fewer inliers than this fraction of the new points
            (unless the visible-overlap test below accepts the fit).
        max_rmse_m: reject when the inliers' RMSE is larger.
        visible_tolerance_m: a carried reference point within this of the depth a new
            camera measured along its pixel is seen; nearer the camera by more, the camera
            saw through it (a contradiction); farther, it is hidden (no evidence). Twice
            the inlier distance: the depth noise at 1-1.5 m plus the reference's voxel.
        min_visible_fitness: accept a fit whose seen / (seen + contradicted) share of the
            reference is at least this. A right fit's contradictions come from silhouette
            pixels only: 0.90-0.97 on generated chairs turned 90 and 180 degrees (rendered
            and simulated views); a fit 3 cm off along the chair scored 0.77-0.84 (and a
            fit 3.2 cm off 0.86, accepted when this bound was 0.85), a yaw 10 degrees off
            0.64-0.77, 30 degrees or more below 0.6. Below it, only a peak is accepted,
            or a fit that climbs to it (``climb_steps_m``).
        min_peak_visible_fitness: a fit below ``min_visible_fitness`` is accepted down to
            this when it is a peak of the visible overlap: no fit moved by
            ``peak_step_m`` along x or y or turned by ``peak_step_deg`` scores higher.
            The overlap a right fit reaches depends on the chair (a chair with thin
            slats, seen from sides the reference saw obliquely, scored 0.80-0.86 with the
            true motion in the simulated world while its 3 cm slips scored 0.42-0.65); a
            fit that is itself off has a neighbour nearer the right one that scores
            higher. The floor stays above the overlap of a yaw 30 degrees off (below 0.6).
        peak_step_m, peak_step_deg: the neighbours of the peak test: an error worth
            rejecting (3 cm moves the bear's seat point off a margin of a few cm).
        request_tolerance_deg: with the turn the helper was asked for, a fit accepted
            only as a peak, or only after the climb, must turn the chair within this of
            it, or of its reverse (a helper who turned the wrong way). From the few
            tracking views, a chair turned half round can match its unturned self better
            than the right fit (the views see sides the reference never saw; both fill
            the same box), and only a peak's overlap is that weak, or a climbed one's (a
            sofa's turn read 180 degrees off climbed to 0.884). One instruction step
            (30 deg): the helper turns by the words, not by the exact angle they round.
        global_voxel_m: downsampling of the FPFH + RANSAC global registration.
        climb_steps_m, climb_steps_deg: the moves (along x and y) and turns (about the
            carried reference's centroid) of the climb on the visible overlap, coarse to
            fine, each kept while it raises the overlap; one turn per move, so equally
            long. The first is about the error ICP leaves on a turned chair (0.5-4 cm);
            the last is a third of the fine voxel. Empty: no climb.
        climb_max_evaluations: bounds the climb's time (each evaluation projects the
            reference into every frame).
    """

    hypothesis_step_deg: float = 30.0
    coarse_voxel_m: float = 0.02
    fine_voxel_m: float = 0.008
    coarse_distance_m: float = 0.06
    fine_distance_m: float = 0.02
    inlier_distance_m: float = 0.015
    min_fitness: float = 0.6
    max_rmse_m: float = 0.01
    visible_tolerance_m: float = 0.03
    min_visible_fitness: float = 0.88
    min_peak_visible_fitness: float = 0.7
    peak_step_m: float = 0.03
    peak_step_deg: float = 5.0
    request_tolerance_deg: float = 30.0
    global_voxel_m: float = 0.02
    climb_steps_m: tuple[float, ...] = (0.01, 0.005, 0.0025)
    climb_steps_deg: tuple[float, ...] = (2.0, 1.0, 0.5)
    climb_max_evaluations: int = 400
