"""passthrough_trajectory_controller over DDS: the driver's passthrough scenarios (integration_test_passthrough_
controller.py: a trajectory and a quintic trajectory succeed, an impossible goal tolerance or goal time tolerance
ends GOAL_TOLERANCE_VIOLATED), and upstream's goal rules (inactive, busy, partial goals), cancel stopping the
robot, and the robot reaching each point at rest when only positions are given."""
from math import pi

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from control_msgs.action import FollowJointTrajectory
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import point, ready_action, running_sim

from ur_common.action_client import ActionClient
from ur_sim_driver.motion import result_codes as rc

NAME = 'passthrough_trajectory_controller'
HOME = np.array([0.0, -1.5708, 0.0, -1.5708, 0.0, 0.0])  # the driver test's HOME, in joint order
WAYPOINTS = [HOME + i * pi / 4 for i in (0, -1, 1)]
TIMES = (4.0, 8.0, 12.0)


@pytest.fixture(scope='module')
def rig():
    with running_sim(initial_positions=HOME.tolist()) as h:
        cm = ControllerManagerClient(h)
        client = ActionClient(h.client, FollowJointTrajectory, f'/{NAME}/follow_joint_trajectory',
                              callback_group=ReentrantCallbackGroup())
        ready_action(client)
        # The passthrough scenarios start from no active joint controller: each test activates its own.
        assert cm.switch(deactivate=['scaled_joint_trajectory_controller']).ok
        h.keeper.remember()
        yield h, cm, client


def send(h, client, goal):
    return h.send(goal, client=client)


def result(h, handle):
    return h.result(handle, timeout=60.0)


def goal(h, velocities=False, accelerations=False, position_tol=None, velocity_tol=0.0, goal_time=0.0,
         names=None):
    zero = [0.0] * 6
    points = [point(q, t, zero if velocities else None, zero if accelerations else None)
              for q, t in zip(WAYPOINTS, TIMES)]
    tol = () if position_tol is None else [(n, position_tol, velocity_tol, 0.0) for n in h.joints]
    return h.goal(points, names=names, goal_tol=tol, goal_time=goal_time)


def activate(cm) -> None:
    # The driver's test: BEST_EFFORT, activate passthrough, deactivate joint_trajectory_controller.
    assert cm.switch(activate=[NAME], deactivate=['joint_trajectory_controller'], strictness=BEST_EFFORT).ok


def test_inactive_controller_rejects_goals(rig):
    h, cm, client = rig
    assert cm.states()[NAME] == 'inactive'
    assert not send(h, client, goal(h)).accepted


def test_passthrough_trajectory(rig):
    h, cm, client = rig
    activate(cm)
    assert cm.states()[NAME] == 'active'
    rec = h.record()
    handle = send(h, client, goal(h, position_tol=0.01, goal_time=1.0))
    assert handle.accepted
    status, code, text = result(h, handle)
    h.stop_recording()
    assert (status, code) == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL), text
    assert 'Trajectory executed successfully in' in text
    assert np.abs(h.q - WAYPOINTS[-1]).max() < 0.01
    # Positions only: the robot is at rest at the intermediate points (a cubic through zero velocities).
    _, q, qd = rec.arrays()
    for k in (1, 2):  # where the arm passes closest to the point, it is there and at rest
        i = int(np.argmin(np.abs(q - WAYPOINTS[k]).max(axis=1)))
        assert np.abs(q[i] - WAYPOINTS[k]).max() < 0.01
        assert np.abs(qd[i]).max() < 0.05, (k, qd[i])


def test_quintic_trajectory(rig):
    h, cm, client = rig
    activate(cm)
    # As the driver's test: a velocity tolerance of 0 (the message's default) against the last point's zero
    # velocities: the robot must report exactly 0.0 when it reports the end (encoder counts, robot/encoders.py).
    handle = send(h, client, goal(h, velocities=True, accelerations=True, position_tol=0.01, velocity_tol=0.0,
                               goal_time=1.0))
    assert handle.accepted
    status, code, text = result(h, handle)
    assert (status, code) == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL), text


def test_impossible_goal_tolerance_fails(rig):
    h, cm, client = rig
    activate(cm)
    handle = send(h, client, goal(h, position_tol=1e-9, goal_time=1.0))
    assert handle.accepted
    status, code, text = result(h, handle)
    assert (status, code, text) == (GoalStatus.STATUS_ABORTED, rc.GOAL_TOLERANCE_VIOLATED,
                                    'Robot not within tolerances at end of trajectory.')


def test_impossible_goal_time_tolerance_fails(rig):
    h, cm, client = rig
    activate(cm)
    handle = send(h, client, goal(h, position_tol=0.01, goal_time=1e-8))
    assert handle.accepted
    status, code, text = result(h, handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.GOAL_TOLERANCE_VIOLATED)
    assert text.startswith('Goal not reached within time tolerance. Missed goal time by ')


def test_rules_busy_partial_and_cancel(rig):
    h, cm, client = rig
    activate(cm)
    # Every joint is required, and goal tolerances name every joint or none.
    assert not send(h, client, h.goal([point(HOME[:5], 4.0)], names=h.joints[:5])).accepted
    partial_tol = h.goal([point(HOME, 4.0)], goal_tol=[(h.joints[0], 0.01, 0.0, 0.0)])
    assert not send(h, client, partial_tol).accepted
    first = send(h, client, goal(h))
    assert first.accepted
    assert not send(h, client, goal(h)).accepted  # no preemption: a trajectory is executing
    h.wait_sim_time(6.0)  # the goal holds HOME until 4 s, then heads for its second waypoint
    h.cancel(first)
    status, _, _ = result(h, first)
    assert status == GoalStatus.STATUS_CANCELED
    # The robot stops where it was.
    h.wait_sim_time(0.5)
    q = h.q
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q).max() < 1e-3
    assert np.abs(q - HOME).max() > 0.05  # it had moved
    # Back to the default controller.
    assert cm.switch(activate=['scaled_joint_trajectory_controller'], deactivate=[NAME]).ok
