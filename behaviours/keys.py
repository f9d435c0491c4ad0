"""The blackboard keys of the mission, one place to read what each holds.

Every key is absolute. Behaviours register the ones they read or write through their
own blackboard client, so ``bearchair tree --blackboard`` shows who touches what.

========================== ====================================================== ==========
key                        value                                                  written by
========================== ====================================================== ==========
/mission/seed              int: the run's seed                                    executive
/mission/arena             core.arena.Arena: walls, obstacles, chair area       executive
/mission/failures          list[str]: every leaf failure message, in order        any leaf
/chair/scan                skills.results.ChairScan                               ScanChair
/chair/mesh                trimesh.Trimesh: the chair now, world frame            ScanChair, MeasureChairRotation
/chair/points              (N, 3) ndarray: the chair now, world frame (ICP ref.)  ScanChair, MeasureChairRotation
/sitting/imagination       skills.results.ImaginationResult                       ImagineSitting
/sitting/pose              core.geometry.SittingPose: g now, world frame        ImagineSitting, CheckAccessibility, MeasureChairRotation
/humanoid/pose             core.se2.SE2Pose: last tracked humanoid pose    CheckAccessibility, WalkToChair
/accessibility/reachable   skills.results.SeatReachability: the chair alone       CheckSeatReachable
/accessibility/result      skills.results.AccessibilityResult (latest check)      CheckAccessibility
/accessibility/se2_goal    core.se2.SE2Pose: where the humanoid stands     CheckAccessibility
/assistance/instructions   list[str]: the sentences said, in order                InstructHelper
/assistance/rotations      int: rotations asked for so far                        InstructHelper
/assistance/measured       list[ChairRotation]: each measured g_rot               MeasureChairRotation
/walk/result               skills.results.WalkResult                              WalkToChair
/seat/plan                 skills.results.SeatingPlan                             SeatBear
/seat/judgement            hardware.interfaces.SeatingJudgement (simulation)      ReleaseAndStand
========================== ====================================================== ==========
"""

SEED = "/mission/seed"
ARENA = "/mission/arena"
FAILURES = "/mission/failures"
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

MAX_ROTATIONS = 3
"""Rotations the helper may be asked for before the mission gives up (the paper)."""
