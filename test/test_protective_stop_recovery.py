"""A protective stop can always be cleared as on the robot, without restarting ur_sim: the arm driven into itself,
into the table and into the glass; unlocked through the dashboard after the robot's 5 s it rests where it stopped
without stopping again, plays on and moves away; a power cycle clears the stop too."""
import numpy as np
from action_msgs.msg import GoalStatus
from sim_harness import RobotKeeper, point, running_sim, wait_for

from ur_glue_planner.execution.ros_conversions import joint_trajectory
from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.approach import joint_move
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.touch import touch_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import tool_axis
from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import NORMAL, PROTECTIVE_STOP, RUNNING

START = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
ELBOW_INTO_ARM = START + np.array([0.0, 0.0, 4.0, 0.0, 0.0, 0.0])  # the wrist meets the upper arm long before 4 rad
INTO_TABLE = np.array([0.0, 0.3, 0.0, 0.0, 0.0, 0.0])  # forearm and wrist below the table top


def _collide(h, target, seconds: float) -> str:
    """Move towards `target` (n,) [rad] in `seconds`; the protective stop's cause, asserted to come."""
    handle = h.send(h.goal([point(target, seconds, np.zeros(6))]))
    assert handle.accepted
    status, code, text = h.result(handle, timeout=seconds + 5.0)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL), text
    assert h.sim.robot.safety_mode == PROTECTIVE_STOP, text
    return h.sim.robot.stop_cause


def _move_back(h, target) -> None:
    params = h.sim.sim.params
    move = joint_move(h.q, target, params.v_max, params.a_max, 0.008, min_duration=2.0)
    goal = h.goal([])
    goal.trajectory = joint_trajectory(h.joints, move.times, move.q, move.qd, move.qdd)
    handle = h.send(goal)
    assert handle.accepted
    status, code, text = h.result(handle, timeout=move.times[-1] + 5.0)
    assert (status, code) == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL), text
    assert h.sim.robot.safety_mode == NORMAL, h.sim.robot.stop_cause


def _unlock_and_play(h, dashboard: RobotKeeper) -> None:
    robot = h.sim.robot
    assert not dashboard.call('unlock_protective_stop').success  # the robot's 5 s have not passed
    wait_for(lambda: robot.unlock_wait() == 0.0, what="the robot's 5 s")
    assert dashboard.call('unlock_protective_stop').success
    h.wait_sim_time(1.0)  # resting where it stopped: no new stop
    assert robot.safety_mode == NORMAL, robot.stop_cause
    assert dashboard.call('play').success
    h.wait_sim_time(0.1)
    assert robot.motion_refusal() is None


def test_the_elbow_driven_into_the_arm_is_unlocked_and_moved_away():
    with running_sim(ur_type='ur5e') as h:
        dashboard = h.keeper
        cause = _collide(h, ELBOW_INTO_ARM, 4.0)
        assert cause.startswith('contact between upper_arm_link and wrist_'), cause  # the arm against itself
        _unlock_and_play(h, dashboard)
        _move_back(h, START)
        # Into it again, and cleared by a power cycle this time (no wait for the 5 s).
        _collide(h, ELBOW_INTO_ARM, 4.0)
        for name in ('power_off', 'power_on', 'brake_release'):
            assert dashboard.call(name).success, name
        h.wait_sim_time(1.5)
        assert (h.sim.robot.robot_mode, h.sim.robot.safety_mode) == (RUNNING, NORMAL), h.sim.robot.stop_cause
        assert dashboard.call('play').success
        h.wait_sim_time(0.1)
        _move_back(h, START)


def test_the_arm_driven_into_the_table_is_unlocked_and_moved_away():
    # At a moderate speed: driven into the table at full speed, the wrist joints give way to the contact (their 28 N m
    # against some 200 N) and the arm folds on along the table after the stop, which no unlock survives.
    with running_sim(ur_type='ur5e') as h:
        dashboard = h.keeper
        cause = _collide(h, INTO_TABLE, 10.0)
        assert ' and floor: force ' in cause, cause
        _unlock_and_play(h, dashboard)
        _move_back(h, START)


def test_the_nozzle_driven_into_the_glass_is_unlocked_and_moved_away():
    job = load_job(default_job_path())
    with running_sim(ur_type=job.ur_type, tool='dispenser', scene='windshield') as h:
        dashboard = h.keeper
        kin = ur_kinematics(job.ur_type, job.tool)
        seg = touch_move(kin, plan_job(job, h.q).bead.q[0], tool_axis(job.tool), height=0.02, depth=0.02,
                         speed=0.15, dt=job.sample_time)
        _move_back(h, seg.q[0])
        goal = h.goal([])
        goal.trajectory = joint_trajectory(h.joints, seg.times, seg.q, seg.qd, seg.qdd)
        handle = h.send(goal)
        assert handle.accepted
        status, code, text = h.result(handle)
        assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL), text
        assert 'contact between dispenser and windshield_piece_' in h.sim.robot.stop_cause
        _unlock_and_play(h, dashboard)
        _move_back(h, seg.q[0])
