"""The real skills, bound for the mission tree: :class:`DefaultSkills`.

Importing this module imports every skill (open3d, casadi, pybullet, OMPL: about 2 s),
which is why the tree's leaves see only the :class:`bearchair.skills.mission_skills.MissionSkills`
protocol and the executive imports this module when a mission runs.
"""

from __future__ import annotations

import functools
import threading

from bearchair.skills import assistance, control, imagination, perception
from bearchair.skills.imagination.drop_records import SimulationSettings
from bearchair.skills.parameters import SkillParameters
from bearchair.skills.perception.reconstruction_config import ReconstructionConfig
from bearchair.skills.planning import accessibility, stance, wholebody
from bearchair.skills.planning.wholebody.optimisation import start_building_problems
from bearchair.skills.planning.wholebody.release_choice import plan_seating_released


class DefaultSkills:
    """The skill functions the mission calls, one attribute each (see ``MissionSkills``).

    Args:
        imagination_workers: processes ``imagine_sitting`` drops in (1: this one).
        parameters: the tuned parameters of the scan and the imagination (None: the
            skills' own defaults).
    """

    scan_chair = staticmethod(perception.scan_chair)
    look_from_above = staticmethod(perception.look_from_above)
    look_at_seat = staticmethod(perception.look_at_seat)
    wait_until_chair_still = staticmethod(perception.wait_until_chair_still)
    measure_chair_rotation = staticmethod(perception.measure_chair_rotation)
    check_seat_reachable = staticmethod(stance.check_seat_reachable)
    check_seat_levels = staticmethod(stance.check_seat_levels)
    check_accessibility = staticmethod(accessibility.check_accessibility)
    choose_rotation = staticmethod(assistance.choose_rotation)
    compose_instruction = staticmethod(assistance.compose_instruction)
    walk_path = staticmethod(control.walk_path)
    raise_bear = staticmethod(wholebody.raise_bear)
    plan_seating = staticmethod(plan_seating_released)
    execute_seating = staticmethod(wholebody.execute_seating)
    release_and_stand = staticmethod(wholebody.release_and_stand)

    def __init__(
        self,
        imagination_workers: int = imagination.DEFAULT_WORKERS,
        parameters: SkillParameters | None = None,
    ) -> None:
        parameters = parameters or SkillParameters()
        self.imagination_workers = imagination_workers
        self.parameters = parameters
        # Where this mission last saw the NAO's tag: the next tracking frame is read out
        # around it (the walk's 10 Hz loop).
        self.locate_humanoid = functools.partial(
            perception.locate_humanoid, sightings=perception.TagSightings()
        )
        settings = _simulation_settings(parameters)
        self.imagine_sitting = functools.partial(
            imagination.imagine_sitting,
            workers=imagination_workers,
            **({} if settings is None else {"settings": settings}),
        )
        if parameters.scan_views is not None or parameters.voxel_size_m is not None:
            self.scan_chair = functools.partial(
                perception.scan_chair,
                views=parameters.scan_views,
                config=_reconstruction(parameters),
            )

    def warm_up(self) -> threading.Thread:
        """Starts building, in the background, what a skill would otherwise build on its
        first call: the whole-body planner's problems (2 s), needed after the scan and the
        imagination."""
        return start_building_problems()


def _simulation_settings(parameters: SkillParameters) -> SimulationSettings | None:
    changed = {
        name: value
        for name, value in (
            ("max_time_s", parameters.max_drop_time_s),
            ("drop_clearance_m", parameters.drop_clearance_m),
        )
        if value is not None
    }
    return SimulationSettings()._replace(**changed) if changed else None


def _reconstruction(parameters: SkillParameters) -> ReconstructionConfig | None:
    if parameters.voxel_size_m is None:
        return None
    return ReconstructionConfig(voxel_size_m=parameters.voxel_size_m)
