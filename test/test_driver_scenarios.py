"""The UR driver's own trajectory test scenarios (ur_robot_driver/test, jazzy) against ur_sim over DDS.

Each runs on ur5e (500 Hz) and ur5 (125 Hz), with and without tf_prefix 'my_ur_', with the joint names in
the order those tests use. The robot is mounted 1 m up: the scenarios stretch the arm out horizontally at
shoulder height, which on the floor would put a UR5's wrist into it (the driver's tests run on URSim, which
has no floor).
"""
import re

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from sim_harness import point, running_sim, trajectory, wait_for, wait_still

from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import PROTECTIVE_STOP

# As the driver's test_common.ROBOT_JOINTS: not the controller's order.
ROBOT_JOINTS = ['elbow_joint', 'shoulder_lift_joint', 'shoulder_pan_joint', 'wrist_1_joint', 'wrist_2_joint',
                'wrist_3_joint']
CONFIGS = [('ur5e', ''), ('ur5e', 'my_ur_'), ('ur5', ''), ('ur5', 'my_ur_')]


@pytest.fixture(scope='module', params=CONFIGS, ids=[f'{t}-{p or "noprefix"}' for t, p in CONFIGS])
def robot(request):
    ur_type, prefix = request.param
    with running_sim(ur_type=ur_type, tf_prefix=prefix, base_pose=[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]) as h:
        h.names = [prefix + j for j in ROBOT_JOINTS]
        h.params = load_ur_params(ur_type)
        yield h


def same_for_all(value):
    return [value] * 6


def test_controller_joints_carry_the_prefix(robot):
    prefix = robot.sim.cfg.tf_prefix
    assert all(j.startswith(prefix) for j in robot.sim.jtc.joint_names)
    assert list(robot.sim.jtc.joint_names) == robot.joints


def test_three_points_succeed_and_decreasing_times_are_rejected(robot):
    h = robot
    goal = h.goal([point(same_for_all(0.0), 6.0), point(same_for_all(-0.5), 9.0), point(same_for_all(-1.0), 12.0)],
                  names=h.names)
    handle = h.send(goal)
    assert handle.accepted
    assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    illegal = h.goal([point(same_for_all(0.0), 6.0), point(same_for_all(-1.0), 3.0)], names=h.names)
    assert not h.send(illegal).accepted


def test_one_rad_in_half_a_second_succeeds_slowed_by_the_robot(robot):
    h = robot
    rec = h.record()
    handle = h.send(h.goal([point(same_for_all(0.0), 6.0), point(same_for_all(-1.0), 6.5)], names=h.names))
    assert handle.accepted
    assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    h.wait_sim_time(0.5)
    h.stop_recording()
    t, q, qd = rec.arrays()
    effort = np.array(rec.effort)
    # The robot slowed itself: its reported factor went well below 100 %.
    assert min(rec.speed_scaling) < 50.0
    # Never above a joint limit, whatever the reference asked.
    assert (np.abs(qd) <= 1.01 * h.params.v_max).all()
    # Efforts are motor currents [A]: within the drives' range, the torque limits over the torque constants.
    assert (np.abs(effort) <= h.params.effort_max / h.params.torque_constant + 1e-9).all()
    # No overshoot past the final point (every joint ends moving down to -1 rad).
    assert (q[t > t[-1] - 1.0] >= -1.0 - 2e-3).all()
    assert np.abs(q[-1] + 1.0).max() < 2e-3


def test_one_rad_in_fifty_ms_violates_the_path_tolerance_then_holds(robot):
    h = robot
    goal = h.goal([point(same_for_all(0.0), 6.0), point(same_for_all(-1.0), 6.05),
                   point(same_for_all(-1.5), 8.0)], names=h.names)
    handle = h.send(goal)
    assert handle.accepted
    status, code, text = h.result(handle, timeout=60)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED)
    assert text == 'Aborted due to path tolerance violation'  # upstream's words; the joint is in the log
    rec = h.record()
    q_abort = h.q
    h.wait_sim_time(2.0)
    h.stop_recording()
    _, q, _ = rec.arrays()
    assert np.abs(q - q_abort).max() < 0.01


def test_jump_at_time_zero_is_a_path_violation_and_the_arm_holds(robot):
    h = robot
    q0 = h.q
    target = q0 + 0.8
    log = h.rosout()
    rec = h.record()
    handle = h.send(h.goal([point(target, 0.0)]))
    assert handle.accepted
    status, code, text = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED)
    assert text == 'Aborted due to path tolerance violation'
    # Which joint, by how much: in the controller's log, as upstream prints it.
    wait_still(lambda: any('exceeds the tolerance' in m for _, m in log), what='the tolerance log line')
    logged = [m for n, m in log if 'exceeds the tolerance' in m and n.endswith('joint_trajectory_controller')]
    error = float(re.search(r'position error ([0-9.]+) rad exceeds the tolerance', logged[-1]).group(1))
    assert abs(error - 0.8) < 1e-3, logged  # the arm settles from the move before by a few 1e-5 rad
    h.wait_sim_time(0.5)
    h.stop_recording()
    _, q, _ = rec.arrays()
    assert np.abs(q - q0).max() < 2e-3


def test_a_target_beyond_the_position_limit_stops_at_the_limit(robot):
    # Accepted, as by the real driver; the robot brakes to a stop at wrist_3's limit (+2 pi), goes no further,
    # and its safety system enters a protective stop, which must be unlocked before it moves again.
    h = robot
    q0 = h.q
    target = q0.copy()
    target[5] = 2 * np.pi + 0.5
    rec = h.record()
    h.topic.publish(trajectory(h.joints, [point(target, 4.0)]))
    wait_for(lambda: h.sim.robot.safety_mode == PROTECTIVE_STOP, what='the protective stop')
    assert 'wrist_3_joint driven into its position limit 6.2832 rad' in h.sim.robot.stop_cause
    h.wait_sim_time(1.0)
    h.stop_recording()
    _, q, qd = rec.arrays()
    assert q[:, 5].max() <= 2 * np.pi + 1e-3
    assert q[-1, 5] > 2 * np.pi - 0.01
    assert (np.abs(qd) <= 1.01 * h.params.v_max).all()
    with h.sim.host.lock:
        assert h.sim.robot.unlock_protective_stop() is not None  # within 5 s: refused
    h.wait_sim_time(5.0)
    with h.sim.host.lock:
        assert h.sim.robot.unlock_protective_stop() is None
        assert h.sim.robot.play() is None
    h.topic.publish(trajectory(h.joints, [point(q0, 4.0)]))
    wait_for(lambda: np.abs(h.q - q0).max() < 1e-3, what='the way back')
