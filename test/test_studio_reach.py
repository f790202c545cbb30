"""Reachability of taught waypoints: IK, joint limits and collisions with the glass, with the reason."""
import numpy as np
import pytest

from ur_common.paths import config_dir
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.studio.reach import GlassCollision, Reach, waypoint_pose
from ur_glue_planner.studio.scene_assets import glass_pieces
from ur_glue_planner.studio.teaching import TeachState
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool

HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])


@pytest.fixture(scope='module')
def reach():
    job = load_job(config_dir() / 'glue_job.yaml')
    kin = ur_kinematics('ur5', 'dispenser')
    return Reach(kin, GlassCollision(load_ur_params('ur5'), get_tool('dispenser'), glass_pieces(job.windshield)))


def test_seed_waypoints_are_reachable_and_the_solution_puts_the_tip_there(reach):
    q = HOME
    for wp in TeachState.defaults().waypoints:
        target = waypoint_pose(wp.position, wp.rotation())
        res = reach.solve(target, q)
        assert res.reachable, res.reason
        assert np.allclose(reach.kin.fk(res.q), target, atol=1e-6)
        assert reach.collision.contacts(res.q) == []
        q = res.q


def test_out_of_reach(reach):
    res = reach.solve(waypoint_pose([1.5, 0.0, 0.2], np.eye(3)), HOME)
    assert not res.reachable and res.reason.startswith('no IK solution: out of reach')


def test_tip_inside_the_glass_is_a_collision(reach):
    wp = TeachState.defaults().waypoints[10]
    res = reach.solve(waypoint_pose(np.array(wp.position) - [0.0, 0.0, 0.03], wp.rotation()), HOME)
    assert not res.reachable
    assert res.reason.startswith('collision with the glass: dispenser') and 'mm into it' in res.reason


def test_joint_limit_is_named(reach):
    # The same arm with the base joint limited to [-0.1, 0.1] rad cannot turn to the first waypoint (-0.40 rad).
    kin = ur_kinematics('ur5', 'dispenser')
    kin.q_min = np.where(np.arange(6) == 0, -0.1, kin.q_min)
    kin.q_max = np.where(np.arange(6) == 0, 0.1, kin.q_max)
    limited = Reach(kin, None)
    wp = TeachState.defaults().waypoints[0]
    target = waypoint_pose(wp.position, wp.rotation())
    assert reach.solve(target, HOME).reachable
    res = limited.solve(target, HOME)
    assert not res.reachable
    assert res.reason.startswith('joint limit: shoulder_pan_joint would need') and '[-0.10, 0.10]' in res.reason
