"""AnnounceSeat: the robot says where the bear will face, before it walks there."""

import math

from bearchair.behaviours import keys
from bearchair.behaviours.skill_behaviour import SkillBehaviour


class AnnounceSeat(SkillBehaviour):
    """Says the imagined sitting direction through the robot's speaker."""

    def __init__(self, name: str = "AnnounceSeat") -> None:
        super().__init__(name, reads=(keys.SITTING_POSE,))

    def prepare(self):  # in the tick: read the blackboard, return the job
        _, robot = self.need()
        yaw_deg = math.degrees(self.blackboard.get(keys.SITTING_POSE).yaw)
        sentence = f"I will seat the bear facing {yaw_deg:.0f} degrees."
        return lambda: robot.speaker.say(sentence)  # runs in a worker thread

    def conclude(self, result):  # in the tick, with the job's result
        return self.succeed("announced the seat")
