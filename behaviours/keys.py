"""The blackboard keys of the mission, one place to read what each holds.

Every key is absolute. Behaviours register the ones they read (READ access) and write
(WRITE access) through their own blackboard client, so ``bearchair tree --blackboard``
shows who touches what. The table below is generated from those registrations
(``bearchair.executive.tree_render.blackboard_table``); a test keeps it in step with the tree.

======================== =========================================================== =========================================================================== =========================================================================================================================================
key                      value                                                       written by                                                                  read by
======================== =========================================================== =========================================================================== =========================================================================================================================================
/mission/seed            int: the run's seed                                         executive                                                                   ScanChair, ImagineSitting, LookFromAbove, LookAtSeat, ImagineOnSeatView, CheckAccessibility, InstructHelper
/mission/arena           bearchair.core.arena.Arena: walls, obstacles, chair area    executive                                                                   CheckAccessibility, InstructHelper
/chair/scan              bearchair.skills.results.ChairScan                          ScanChair, LookFromAbove, LookAtSeat                                        LookFromAbove, LookAtSeat
/chair/mesh              trimesh.Trimesh: the chair now, world frame                 ScanChair, LookFromAbove, LookAtSeat, MeasureChairRotation                  ImagineSitting, NoSittingFound, ImagineOnSeatView, CheckSeatReachable, CheckAccessibility, InstructHelper, MeasureChairRotation, SeatBear
/chair/points            (N, 3) ndarray: the chair now, world frame (ICP ref.)       ScanChair, LookFromAbove, LookAtSeat, MeasureChairRotation                  MeasureChairRotation
/chair/seat_view         str: the view LookAtSeat added over p ('': none)            LookAtSeat                                                                  ImagineOnSeatView
/sitting/imagination     bearchair.skills.results.ImaginationResult                  ImagineSitting, ImagineOnSeatView                                           LookFromAbove
/sitting/pose            bearchair.core.geometry.SittingPose: g now, world frame     ImagineSitting, ImagineOnSeatView, CheckAccessibility, MeasureChairRotation ImagineSitting, LookAtSeat, CheckSeatReachable, CheckAccessibility, InstructHelper, MeasureChairRotation, SeatBear, ReleaseAndStand
/humanoid/pose           bearchair.core.se2.SE2Pose: last tracked humanoid pose      CheckAccessibility
/accessibility/reachable bearchair.skills.results.SeatReachability: the chair alone  CheckSeatReachable
/accessibility/result    bearchair.skills.results.AccessibilityResult (latest check) CheckAccessibility                                                          WalkToChair, SeatBear
/accessibility/se2_goal  bearchair.core.se2.SE2Pose: where the humanoid stands       CheckAccessibility
/assistance/instructions list[str]: the sentences said, in order                     InstructHelper                                                              InstructHelper
/assistance/rotations    int: rotations asked for so far                             InstructHelper                                                              InstructHelper, GiveUp
/assistance/requested    float: the last turn asked for, rad, counterclockwise +     InstructHelper                                                              MeasureChairRotation
/assistance/measured     list[ChairRotation]: each measured g_rot                    MeasureChairRotation                                                        MeasureChairRotation
/walk/result             bearchair.skills.results.WalkResult                         WalkToChair
/seat/plan               bearchair.skills.results.SeatingPlan                        SeatBear                                                                    ReleaseAndStand
/seat/judgement          bearchair.hardware.interfaces.SeatingJudgement (simulation) ReleaseAndStand
======================== =========================================================== =========================================================================== =========================================================================================================================================
"""

SEED = "/mission/seed"
ARENA = "/mission/arena"
CHAIR_SCAN = "/chair/scan"
CHAIR_MESH = "/chair/mesh"
CHAIR_POINTS = "/chair/points"
SEAT_VIEW = "/chair/seat_view"
IMAGINATION = "/sitting/imagination"
SITTING_POSE = "/sitting/pose"
HUMANOID_POSE = "/humanoid/pose"
REACHABILITY = "/accessibility/reachable"
ACCESSIBILITY = "/accessibility/result"
SE2_GOAL = "/accessibility/se2_goal"
INSTRUCTIONS = "/assistance/instructions"
ROTATIONS = "/assistance/rotations"
REQUESTED_ROTATION = "/assistance/requested"
MEASURED_ROTATIONS = "/assistance/measured"
WALK = "/walk/result"
SEATING_PLAN = "/seat/plan"
JUDGEMENT = "/seat/judgement"

VALUES = {
    SEED: "int: the run's seed",
    ARENA: "bearchair.core.arena.Arena: walls, obstacles, chair area",
    CHAIR_SCAN: "bearchair.skills.results.ChairScan",
    CHAIR_MESH: "trimesh.Trimesh: the chair now, world frame",
    CHAIR_POINTS: "(N, 3) ndarray: the chair now, world frame (ICP ref.)",
    SEAT_VIEW: "str: the view LookAtSeat added over p ('': none)",
    IMAGINATION: "bearchair.skills.results.ImaginationResult",
    SITTING_POSE: "bearchair.core.geometry.SittingPose: g now, world frame",
    HUMANOID_POSE: "bearchair.core.se2.SE2Pose: last tracked humanoid pose",
    REACHABILITY: "bearchair.skills.results.SeatReachability: the chair alone",
    ACCESSIBILITY: "bearchair.skills.results.AccessibilityResult (latest check)",
    SE2_GOAL: "bearchair.core.se2.SE2Pose: where the humanoid stands",
    INSTRUCTIONS: "list[str]: the sentences said, in order",
    ROTATIONS: "int: rotations asked for so far",
    REQUESTED_ROTATION: "float: the last turn asked for, rad, counterclockwise +",
    MEASURED_ROTATIONS: "list[ChairRotation]: each measured g_rot",
    WALK: "bearchair.skills.results.WalkResult",
    SEATING_PLAN: "bearchair.skills.results.SeatingPlan",
    JUDGEMENT: "bearchair.hardware.interfaces.SeatingJudgement (simulation)",
}
"""What each key holds: the ``value`` column of the table above."""

SET_BY_EXECUTIVE = (SEED, ARENA)
"""The keys written before the first tick, by the executive or any other host, with
:func:`bearchair.behaviours.mission_inputs.set_mission_inputs`."""

MAX_ROTATIONS = 3
"""Rotations the helper may be asked for before the mission gives up (the paper)."""
