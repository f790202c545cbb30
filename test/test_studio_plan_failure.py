"""A plan that fails on a taught waypoint the robot cannot reach says which waypoint and why, as the Teach tab does."""
import numpy as np
import pytest

from ur_common.paths import config_dir
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import windshield_model
from ur_glue_planner.studio.job_file import read_job, studio_job, teach_state
from ur_glue_planner.studio.plan_failure import MAX_CHARS, gist, plan_failure, short_reason
from ur_glue_planner.studio.reach import GlassCollision, Reach, ReachResult, waypoint_pose
from ur_glue_planner.studio.scene_assets import glass_pieces
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool

BRANCHES = ('no IK branch follows the whole bead (branch [-0.44, -1.86, -1.49, -4.26, -1.1, -2.06]: IK fails at '
            's = 0.258 m (out of reach in this arm configuration); branch [2.19, -1.64, 2.06, -2.44, -1.87, 0.55]: '
            'IK fails at s = 1.271 m (out of reach in this arm configuration))')


def test_a_saved_waypoint_out_of_reach_is_named_as_the_page_numbers_it():
    sjob = read_job(config_dir() / 'glue_job.yaml')
    job = sjob.job
    glass = windshield_model(job.windshield)
    teach = teach_state(job)
    moved = np.array(teach.waypoints[12].position) + [0.09, 0.045, 0.0]  # 10 cm further out, on the glass
    teach = teach.move(12, glass.project(moved[None])[1][0])
    assert teach.waypoints[12].saved and 12 in teach.planned_indices()
    with pytest.raises(PlanningError) as failure:
        plan_job(studio_job(sjob, teach).job, np.array(job.home))
    assert str(failure.value).startswith('no IK branch follows the whole bead (') and len(str(failure.value)) > 500
    reach = Reach(ur_kinematics('ur5', 'dispenser'),
                  GlassCollision(load_ur_params('ur5'), get_tool('dispenser'), glass_pieces(job.windshield)))
    results, q = [], np.array(job.home)
    for wp in teach.waypoints:  # as the page checks them: each from its predecessor's solution
        normal = glass.project(np.array(wp.position)[None])[2][0]
        results.append(reach.solve(waypoint_pose(wp.position, wp.rotation(), normal, job.standoff), q))
        q = results[-1].q if results[-1].reachable else q
    message = plan_failure(str(failure.value), results, teach.planned_indices())
    assert message.startswith('waypoint 13: out of reach (') and message.endswith(' mm)'), message
    assert 10 <= int(message.split('(')[1].split()[0]) <= 60  # a few cm beyond the arm's reach


def test_reasons_are_short_and_only_planned_waypoints_count():
    assert short_reason('no IK solution: out of reach (residual 48.2 mm, 3.0 deg)') == 'out of reach (48 mm)'
    limit = 'joint limit: shoulder_pan_joint would need 3.50 rad, limits [-0.10, 0.10]'
    assert short_reason(limit) == limit
    bad = ReachResult(np.zeros(6), False, 'collision with the glass: dispenser 3.2 mm into it')
    good = ReachResult(np.zeros(6), True, '')
    results = [good, bad, bad, None, bad, bad, bad]
    assert plan_failure('x', results, [0, 1]) == 'waypoint 2: collision with the glass: dispenser 3.2 mm into it'
    assert plan_failure('x', results, [0, 2, 4, 5, 6]).endswith('waypoint 6: collision with the glass: '
                                                                 'dispenser 3.2 mm into it; and 1 more unreachable')
    assert plan_failure('singular Jacobian at s = 0.3 m', results, [0, 3]) == 'singular Jacobian at s = 0.3 m'


def test_the_planners_words_in_short_when_every_waypoint_is_reachable():
    assert gist(BRANCHES).startswith('no IK branch follows the whole bead: the best stops 1.271 m along it')
    assert len(gist('x ' * 500)) == MAX_CHARS
