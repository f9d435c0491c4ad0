"""The blackboard keys of the mission, one place to read what each holds.

Every key is absolute. Behaviours register the ones they read (READ access) and write
(WRITE access) through their own blackboard client, so ``bearchair tree --blackboard``
shows who touches what. The table below is generated from those registrations
(``executive.render.blackboard_table``); a test keeps it in step with the tree.

======================== ===================================================== ======================================================== =======================================================================================================
key                      value                                                 written by                                               read by
======================== ===================================================== ======================================================== =======================================================================================================
/mission/seed            int: the run's seed                                   executive                                                ScanChair, ImagineSitting, CheckAccessibility, InstructHelper
/mission/arena           core.arena.Arena: walls, obstacles, chair area        executive                                                CheckAccessibility, InstructHelper
/chair/scan              skills.results.ChairScan                              ScanChair
/chair/mesh              trimesh.Trimesh: the chair now, world frame           ScanChair, MeasureChairRotation                          ImagineSitting, CheckSeatReachable, CheckAccessibility, InstructHelper, MeasureChairRotation, SeatBear
/chair/points            (N, 3) ndarray: the chair now, world frame (ICP ref.) ScanChair, MeasureChairRotation                          MeasureChairRotation
/sitting/imagination     skills.results.ImaginationResult                      ImagineSitting
/sitting/pose            core.geometry.SittingPose: g now, world frame         ImagineSitting, CheckAccessibility, MeasureChairRotation CheckSeatReachable, CheckAccessibility, InstructHelper, MeasureChairRotation, SeatBear, ReleaseAndStand
/humanoid/pose           core.se2.SE2Pose: last tracked humanoid pose          CheckAccessibility
/accessibility/reachable skills.results.SeatReachability: the chair alone      CheckSeatReachable
/accessibility/result    skills.results.AccessibilityResult (latest check)     CheckAccessibility                                       WalkToChair, SeatBear
/accessibility/se2_goal  core.se2.SE2Pose: where the humanoid stands           CheckAccessibility
/assistance/instructions list[str]: the sentences said, in order               InstructHelper                                           InstructHelper
/assistance/rotations    int: rotations asked for so far                       InstructHelper                                           InstructHelper, GiveUp
/assistance/measured     list[ChairRotation]: each measured g_rot              MeasureChairRotation                                     MeasureChairRotation
/walk/result             skills.results.WalkResult                             WalkToChair
/seat/plan               skills.results.SeatingPlan                            SeatBear                                                 ReleaseAndStand
/seat/judgement          hardware.interfaces.SeatingJudgement (simulation)     ReleaseAndStand
======================== ===================================================== ======================================================== =======================================================================================================
"""

SEED = "/mission/seed"
ARENA = "/mission/arena"
CHAIR_SCAN = "/chair/scan"
CHAIR_MESH = "/chair/mesh"
CHAIR_POINTS = "/chair/points"
IMAGINATION = "/sitting/imagination"
SITTING_POSE = "/sitting/pose"
HUMANOID_POSE = "/humanoid/pose"
REACHABILITY = "/accessibility/reachable"
ACCESSIBILITY = "/accessibility/result"
SE2_GOAL = "/accessibility/se2_goal"
INSTRUCTIONS = "/assistance/instructions"
ROTATIONS = "/assistance/rotations"
MEASURED_ROTATIONS = "/assistance/measured"
WALK = "/walk/result"
SEATING_PLAN = "/seat/plan"
JUDGEMENT = "/seat/judgement"

VALUES = {
    SEED: "int: the run's seed",
    ARENA: "core.arena.Arena: walls, obstacles, chair area",
    CHAIR_SCAN: "skills.results.ChairScan",
    CHAIR_MESH: "trimesh.Trimesh: the chair now, world frame",
    CHAIR_POINTS: "(N, 3) ndarray: the chair now, world frame (ICP ref.)",
    IMAGINATION: "skills.results.ImaginationResult",
    SITTING_POSE: "core.geometry.SittingPose: g now, world frame",
    HUMANOID_POSE: "core.se2.SE2Pose: last tracked humanoid pose",
    REACHABILITY: "skills.results.SeatReachability: the chair alone",
    ACCESSIBILITY: "skills.results.AccessibilityResult (latest check)",
    SE2_GOAL: "core.se2.SE2Pose: where the humanoid stands",
    INSTRUCTIONS: "list[str]: the sentences said, in order",
    ROTATIONS: "int: rotations asked for so far",
    MEASURED_ROTATIONS: "list[ChairRotation]: each measured g_rot",
    WALK: "skills.results.WalkResult",
    SEATING_PLAN: "skills.results.SeatingPlan",
    JUDGEMENT: "hardware.interfaces.SeatingJudgement (simulation)",
}
"""What each key holds: the ``value`` column of the table above."""

SET_BY_EXECUTIVE = (SEED, ARENA)
"""The keys the executive writes before the first tick (``executive.runner``)."""

MAX_ROTATIONS = 3
"""Rotations the helper may be asked for before the mission gives up (the paper)."""
