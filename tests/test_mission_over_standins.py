"""The whole mission through the real backends, over the SDK stand-ins, with the
simulated world behind them: qi networking to a NAOqi stand-in, panda-py's and OpenNI's
call shapes, the simulation's clock, helper and judge. Checks the calls each skill made
by name and argument shape."""

from __future__ import annotations

import numpy as np
import pytest

from bearchair.core.arena import DEFAULT_ARENA
from bearchair.executive.records.run_summary import RunInfo
from bearchair.executive.runner import MissionRunner, summarise
from bearchair.hardware.real.panda import wall_limits
from bearchair.hardware.sim.world import SimConfig, SimWorld
from bearchair.skills.default_skills import DefaultSkills
from bearchair.trees.mission import create_tree

pytest.importorskip("qi")


def test_flange_kinematics_of_the_fake_panda_match_the_simulated_panda():
    from bearchair.hardware.real.standins import panda_flange_pose
    from bearchair.hardware.real.standins.simulated_bodies import SimulatedPanda
    from bearchair.hardware.sim.bullet import T_world_link, link_index_by_name

    with SimWorld(SimConfig(seed=0, camera_noise=False)) as world:
        panda = SimulatedPanda(world)
        link8 = link_index_by_name(world._bullet, world.panda.body)["panda_link8"]
        q = world.panda.joint_positions()
        flange = T_world_link(world._bullet, world.panda.body, link8)
        np.testing.assert_allclose(panda_flange_pose(q), flange, atol=1e-6)
        state = panda.get_state()
        O_T_EE = np.asarray(state.O_T_EE).reshape(4, 4).T
        F_T_EE = np.asarray(state.F_T_EE).reshape(4, 4).T
        np.testing.assert_allclose(O_T_EE @ np.linalg.inv(F_T_EE), flange, atol=1e-6)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_the_mission_runs_over_the_sdk_standins():
    from bearchair.hardware.real.standins import NaoqiStandin
    from bearchair.hardware.real.standins.simulated_bodies import (
        SimulatedNaoBody,
        robot_over_standins,
    )

    with (
        SimWorld(SimConfig(seed=1)) as world,
        NaoqiStandin(body=SimulatedNaoBody(world)) as standin,
    ):
        robot, session = robot_over_standins(world, standin)
        robot.humanoid.activate()
        runner = MissionRunner(
            create_tree(), DefaultSkills(), robot, seed=1, arena=DEFAULT_ARENA, timeout_s=900
        )
        summary = summarise(runner.run(), RunInfo())
        panda_calls = list(robot.arm._robot._impl.calls)  # the fake behind the SDK double
        session.close()
    assert summary.outcome == "success", f"{summary.failed_stage}: {summary.reason}"
    assert summary.judgement is not None and summary.judgement.seated

    calls = [(name, args) for _, name, args in standin.calls]
    names = {name for name, _ in calls}
    assert {"move", "angleInterpolation", "openHand", "getRobotPosition"} <= names
    assert "moveTo" not in names  # NAOqi's blocking walk is never used for tracking
    for name, args in calls:
        if name == "move":  # a velocity within the NAO's walking limits
            assert len(args) == 3 and all(isinstance(v, float) for v in args)
            assert abs(args[0]) <= 0.1001 and abs(args[1]) <= 0.0801 and abs(args[2]) <= 0.5001
        elif name == "angleInterpolation":
            joints, angles, times, absolute = args
            assert absolute is True and all(isinstance(j, str) for j in joints)
            assert len(angles) == len(times) == len(joints)
            assert all(len(a) == len(t) for a, t in zip(angles, times, strict=True))
        elif name in ("openHand", "closeHand"):
            assert args in (("LHand",), ("RHand",))
    assert [args[0] for name, args in calls if name == "say"] == list(summary.instructions)
    # The run ended with the emergency stop: the walk stopped, no leg task killed mid-walk.
    assert "stopMove" in names and standin.fell == ""

    lower, upper = wall_limits()
    moves = [args for name, args in panda_calls if name == "move_to_joint_position"]
    assert len(moves) >= 11  # HOME, 9 views, HOME, the overview...
    for joints, speed_factor in moves:
        assert len(joints) == 7 and speed_factor == 0.2
        assert np.all(np.asarray(joints) >= lower - 1e-9) and np.all(
            np.asarray(joints) <= upper + 1e-9
        )
    assert ("Robot.stop", ()) in panda_calls
