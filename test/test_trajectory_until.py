"""/trajectory_until_node/execute over DDS, without contact: the trajectory runs to its end (NOT_TRIGGERED), feedback
is passed on, a second goal is refused while one runs, cancel ends both, and goals are refused when the until
condition's controller does not take its goal (the driver's trajectory_until_node)."""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import STRICT, ControllerManagerClient
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import point, running_sim, trajectory, wait_for, wait_still
from ur_msgs.action import FollowJointTrajectoryUntil as Until

from ur_common.action_client import ActionClient  # rclpy's loses a fast goal response

TOOL = 'tool_contact_controller'
ZERO = [0.0] * 6


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.cm = ControllerManagerClient(h)
        h.until = ActionClient(h.client, Until, '/trajectory_until_node/execute',
                               callback_group=ReentrantCallbackGroup())
        wait_still(h.until.server_is_ready, what='the trajectory_until action server')
        yield h  # the action client goes with the harness's client node, after its executor stopped


def _send(h, seconds: float, feedback=None, until_type=Until.Goal.TOOL_CONTACT):
    goal = Until.Goal(trajectory=trajectory(h.joints, [point(h.q + np.array([0.2, 0, 0, 0, 0, 0]), seconds, ZERO)]),
                      until_type=until_type)
    future = h.until.send_goal_async(goal, feedback_callback=feedback)
    wait_still(future.done, timeout=30.0, what='the until goal answer')
    return future.result()


def _result(handle):
    future = handle.get_result_async()
    wait_for(future.done, 30.0, 'the until result')
    return future.result()


def test_refused_without_an_active_tool_contact_controller(robot):
    # No action client before the first goal: an idle node does not take every status array of the trajectory
    # action (a goal storm's cost the simulation loop shared). First in the module: no goal has come yet.
    node = next(c for c in robot.sim.components if c.name == 'trajectory_until_node')
    assert node._trajectory_client is None and node._until_client is None
    assert robot.cm.states()[TOOL] == 'inactive'
    assert not _send(robot, 1.0).accepted
    assert node._trajectory_client is not None  # made by the goal, kept


def test_runs_to_the_end_without_contact(robot):
    h = robot
    assert h.cm.switch(activate=[TOOL], strictness=STRICT).ok
    feedback = []
    handle = _send(h, 1.0, feedback=feedback.append)
    assert handle.accepted
    assert not _send(h, 1.0).accepted  # busy
    result = _result(handle)
    assert result.status == GoalStatus.STATUS_SUCCEEDED
    assert result.result.error_code == Until.Result.SUCCESSFUL
    assert result.result.until_condition_result == Until.Result.NOT_TRIGGERED
    assert feedback and list(feedback[-1].feedback.joint_names) == h.joints
    # passed on in the order the controller sent it (its stamps never go back)
    stamps = [f.feedback.header.stamp.sec + f.feedback.header.stamp.nanosec * 1e-9 for f in feedback]
    assert np.all(np.diff(stamps) > 0.0), np.diff(stamps)
    # The until goal was cancelled with it (asynchronously, as upstream): once it has ended, a new goal is taken.
    tool = next(c for c in h.sim.components if c.name == TOOL)
    wait_still(lambda: not tool.watching, what='the tool contact goal cancelled')
    handle = _send(h, 0.5)
    assert handle.accepted and _result(handle).status == GoalStatus.STATUS_SUCCEEDED


def test_unknown_until_type_is_refused(robot):
    assert not _send(robot, 1.0, until_type=7).accepted


def test_cancel_ends_both(robot):
    h = robot
    if h.cm.states()[TOOL] != 'active':
        assert h.cm.switch(activate=[TOOL], strictness=STRICT).ok
    handle = _send(h, 3.0)
    assert handle.accepted
    future = handle.cancel_goal_async()
    wait_still(future.done, what='the cancel answer')
    assert future.result().return_code == 0
    result = _result(handle)
    assert result.status == GoalStatus.STATUS_CANCELED
    assert 'canceled' in result.result.error_string
