"""FollowJointTrajectory on a running ur_sim: result codes from real scenarios, feedback, preemption, cancel."""
import re

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from sim_harness import point, running_sim, wait_for, wait_still

from ur_sim_driver.motion import result_codes as rc

HOME = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
TARGET = np.array([0.4, -1.3, 0.4, -1.4, 0.3, 0.2])
ZERO = np.zeros(6)


@pytest.fixture(scope='module')
def h():
    with running_sim() as harness:
        yield harness


def test_success_reaches_target_and_reports_feedback(h):
    feedback = []
    handle = h.send(h.goal([point(TARGET, 1.0, ZERO)]), feedback=feedback.append)
    assert handle.accepted
    status, code, text = h.result(handle)
    assert (status, code, text) == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL, 'Goal successfully reached!')
    assert np.abs(h.q - TARGET).max() < 0.01
    wait_for(lambda: feedback, what='feedback')
    fb = feedback[-1].feedback
    assert list(fb.joint_names) == h.joints
    assert len(fb.desired.positions) == len(fb.actual.positions) == len(fb.error.positions) == 6
    # action_monitor_rate 20 Hz of simulated time: the feedback is stamped every 50 ms of the 1 s motion. The count
    # received is not asserted: at many times real time, DDS keeps only the newest of a burst (a loaded machine
    # dropped all but 4 of 20).
    stamps = np.array([f.feedback.header.stamp.sec + f.feedback.header.stamp.nanosec * 1e-9 for f in feedback])
    assert 1 <= len(stamps) <= 21
    steps = np.diff(stamps) / 0.05
    assert np.all(steps >= 1.0 - 1e-6) and np.allclose(steps, np.round(steps), atol=1e-6), np.diff(stamps)


def test_path_tolerance_violated_by_a_jump(h):
    # A first point at time 0 makes the reference jump there at once (upstream skips the first segment).
    jump = h.q + np.array([0.0, 0.0, 0.0, 0.0, 0.5, 0.0])
    log = h.rosout()
    handle = h.send(h.goal([point(jump, 0.0), point(jump, 1.0)]))
    assert handle.accepted
    status, code, text = h.result(handle)
    assert status == GoalStatus.STATUS_ABORTED
    assert code == rc.PATH_TOLERANCE_VIOLATED
    assert text == 'Aborted due to path tolerance violation'  # upstream's words; the joint is in the log
    wait_still(lambda: any('wrist_2_joint position error' in m for _, m in log), what='the log line naming the joint')
    # After the abort the robot stops near where it was (the measured position at the abort, plus the
    # braking distance of a joint that was accelerating), far from the jump target.
    q_abort = h.q
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q_abort).max() < 0.05
    assert abs(h.q[4] - jump[4]) > 0.4
    assert np.abs(h.sim.sim.state().qd).max() < 0.01


def test_goal_tolerance_violated_after_goal_time(h):
    start = h.q
    target = start + np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    # A 1e-7 rad goal tolerance cannot be met; with goal_time 0.05 s the goal ends with -5.
    tol = [(n, 1e-7, 0.0, 0.0) for n in h.joints]
    handle = h.send(h.goal([point(target, 0.5, ZERO)], goal_tol=tol, goal_time=0.05))
    status, code, text = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.GOAL_TOLERANCE_VIOLATED)
    missed = re.fullmatch(r'Aborted due to goal_time_tolerance exceeding by ([0-9.]+) seconds', text)
    assert missed is not None and float(missed.group(1)) > 0.05, text


def test_path_tolerance_minus_one_disables_the_check(h):
    jump = h.q + np.array([0.0, 0.0, 0.0, 0.0, 0.3, 0.0])
    tol = [(n, -1.0, 0.0, 0.0) for n in h.joints]
    handle = h.send(h.goal([point(jump, 0.0), point(jump, 1.0)], path_tol=tol))
    status, code, _ = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)


def test_preemption_aborts_the_old_goal(h):
    first = h.send(h.goal([point(h.q + 0.3, 3.0, ZERO)]))
    h.wait_sim_time(0.2)
    second = h.send(h.goal([point(HOME, 1.5, ZERO)]))
    status, code, text = h.result(first)
    assert (status, code, text) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL,
                                    'Current goal preempted by new incoming action.')
    assert h.result(second)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    assert np.abs(h.q - HOME).max() < 0.01


def test_cancel_then_hold_measured_position(h):
    # A long goal: the cancel travels through the gateway process while the simulation runs as fast as it can.
    handle = h.send(h.goal([point(h.q + np.array([0.8, 0, 0, 0, 0, 0]), 20.0, ZERO)]))
    h.wait_sim_time(4.0)
    h.cancel(handle)
    status, code, text = h.result(handle)
    # An empty result, as upstream's goal_cancelled_callback gives it.
    assert (status, code, text) == (GoalStatus.STATUS_CANCELED, rc.SUCCESSFUL, '')
    q_cancel = h.q
    assert abs(q_cancel[0] - HOME[0]) > 0.05  # it had moved, and stopped short of the target
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q_cancel).max() < 0.02
    assert np.abs(h.sim.sim.state().qd).max() < 0.01


def test_invalid_goals_are_rejected_and_the_robot_holds(h):
    q0 = h.q
    names = h.joints
    bad_goals = {
        'wrong joint count': h.goal([point(q0[:5], 1.0)], names=names[:5]),
        'unknown joint': h.goal([point(q0, 1.0)], names=names[:5] + ['elbow']),
        'no points': h.goal([]),
        'non-increasing time': h.goal([point(q0, 1.0), point(q0, 1.0)]),
        'nonzero end velocity': h.goal([point(q0, 1.0, np.full(6, 0.1))]),
        'size mismatch': h.goal([point(q0, 1.0, np.zeros(5))]),
        'not finite': h.goal([point(q0 + np.array([np.nan, 0, 0, 0, 0, 0]), 1.0)]),
    }
    old = h.goal([point(q0, 0.001)])
    old.trajectory.header.stamp.nanosec = 1_000_000  # sim time 0.001 s: ends long before now
    bad_goals['end already past'] = old
    duplicate = h.goal([point(q0, 1.0)], names=names[:5] + ['shoulder_pan_joint'])
    bad_goals['duplicate joint'] = duplicate
    effort = h.goal([point(q0, 1.0)])
    effort.trajectory.points[0].effort = [0.0] * 6
    bad_goals['effort given'] = effort
    for what, goal in bad_goals.items():
        handle = h.send(goal)
        assert not handle.accepted, what
    assert np.abs(h.q - q0).max() < 1e-3
    # ... and the node keeps serving.
    ok = h.send(h.goal([point(q0, 0.2, ZERO)]))
    assert ok.accepted and h.result(ok)[1] == rc.SUCCESSFUL
