"""The driver's own motion scenarios, each against a ur_sim started as that test file's launch description starts the
driver (powered off, headless, the dashboard client; ``sim_harness.driver_test_launch``) and the robot started by
upstream's sequence before every test (``sim_harness.start_robot``): scaled_joint_controller, passthrough_controller,
trajectory_until and example_move (ur_robot_driver/test at a16a268). Trajectories name the joints in the order
upstream's tests do. docs/upstream_tests.md maps each upstream test method to the tests that cover it."""
from __future__ import annotations

from math import pi

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from control_msgs.action import FollowJointTrajectory
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import driver_test_launch, point, ready_action, start_robot, wait_for, wait_still
from ur_msgs.action import FollowJointTrajectoryUntil as Until

from ur_common.action_client import ActionClient  # rclpy's loses a goal response that comes fast
from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import POWER_OFF

pytestmark = pytest.mark.timeout(240)
# The order upstream's test helpers list the joints in (the controllers' is shoulder_pan first).
UPSTREAM_ORDER = ['elbow_joint', 'shoulder_lift_joint', 'shoulder_pan_joint', 'wrist_1_joint', 'wrist_2_joint',
                  'wrist_3_joint']
SCALED, PASS, TOOL = ('scaled_joint_trajectory_controller', 'passthrough_trajectory_controller',
                      'tool_contact_controller')


@pytest.fixture(scope='class')
def driver(request):
    """ur_sim as the driver's test launch description starts the driver: (tf_prefix, initial joint controller) the
    class's parameter; the robot started once, so that each test is brought back to that."""
    prefix, initial = getattr(request, 'param', ('', SCALED))
    with driver_test_launch(tf_prefix=prefix, initial_joint_controller=initial) as h:
        assert h.sim.robot.robot_mode == POWER_OFF
        h.cm = ControllerManagerClient(h)
        h.names = [prefix + j for j in UPSTREAM_ORDER]
        start_robot(h)
        h.keeper.remember()
        yield h


@pytest.fixture
def robot(driver):
    """Each test begins with the start sequence, as upstream's setUp does."""
    start_robot(driver)
    return driver


def action(h, controller: str) -> ActionClient:
    """The FollowJointTrajectory client of `controller`, made once per ur_sim (it goes with the harness's node)."""
    clients = h.actions = getattr(h, 'actions', {})
    if controller not in clients:
        clients[controller] = ActionClient(h.client, FollowJointTrajectory, f'/{controller}/follow_joint_trajectory',
                                           callback_group=ReentrantCallbackGroup())
        ready_action(clients[controller])
    return clients[controller]


def each(value: float) -> list[float]:
    return [value] * 6


PREFIXED = [('', SCALED), ('my_ur_', SCALED)]
IDS = ['noprefix', 'my_ur_']


# ---- integration_test_scaled_joint_controller.py -------------------------------------------------------------------
@pytest.mark.parametrize('driver', PREFIXED, indirect=True, ids=IDS)
class TestScaledJointController:
    def test_active_after_the_start_and_three_points_run_and_decreasing_times_are_refused(self, robot):
        h = robot
        assert h.cm.states()[SCALED] == 'active'
        assert h.cm.switch(activate=[SCALED], deactivate=[PASS], strictness=BEST_EFFORT).ok
        handle = h.send(h.goal([point(each(0.0), 6.0), point(each(-0.5), 9.0), point(each(-1.0), 12.0)],
                               names=h.names))
        assert handle.accepted
        assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
        assert np.abs(h.q - (-1.0)).max() < 0.01
        assert not h.send(h.goal([point(each(0.0), 6.0), point(each(-0.5), 3.0)], names=h.names)).accepted

    def test_a_rad_in_half_a_second_is_slowed_by_the_robot_and_succeeds(self, robot):
        h = robot
        rec = h.record()
        handle = h.send(h.goal([point(each(0.0), 6.0), point(each(-1.0), 6.5)], names=h.names))
        assert handle.accepted
        assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
        h.stop_recording()
        assert min(rec.speed_scaling) < 100.0  # the robot, not the trajectory, set the pace of the last half second

    def test_an_infeasible_jump_aborts_on_the_path_tolerance_and_the_arm_stays(self, robot):
        h = robot
        handle = h.send(h.goal([point(each(0.0), 6.0), point(each(-1.0), 6.05), point(each(-1.5), 8.0)],
                               names=h.names))
        assert handle.accepted
        assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED)
        stopped = h.q
        h.wait_sim_time(2.0)
        assert np.abs(h.q - stopped).max() < 0.01


# ---- integration_test_passthrough_controller.py --------------------------------------------------------------------
HOME = {'elbow_joint': 0.0, 'shoulder_lift_joint': -1.5708, 'shoulder_pan_joint': 0.0, 'wrist_1_joint': -1.5708,
        'wrist_2_joint': 0.0, 'wrist_3_joint': 0.0}
# Upstream's four cases, each run once, split between the two tf_prefixes: (tf_prefix, what the goal says: with
# velocities and accelerations (quintic), its goal tolerance [rad], goal time tolerance [s], the result expected)
PASSTHROUGH_CASES = [('', False, 0.01, 1.0, rc.SUCCESSFUL), ('my_ur_', True, 0.01, 1.0, rc.SUCCESSFUL),
                     ('', False, 1e-9, 1.0, rc.GOAL_TOLERANCE_VIOLATED),
                     ('my_ur_', False, 0.01, 1e-8, rc.GOAL_TOLERANCE_VIOLATED)]


@pytest.mark.timeout(300)
@pytest.mark.parametrize('driver, quintic, tolerance, goal_time, expected',
                         [((prefix, SCALED), *case) for prefix, *case in PASSTHROUGH_CASES], indirect=['driver'],
                         ids=['positions', 'quintic', 'tight-tolerance', 'tight-goal-time'])
class TestPassthroughController:
    def test_the_robot_runs_the_trajectory_and_judges_the_goal(self, robot, quintic, tolerance, goal_time,
                                                               expected):
        h = robot
        client = action(h, PASS)
        assert h.cm.switch(activate=[PASS], deactivate=[SCALED], strictness=BEST_EFFORT).ok
        zero = each(0.0) if quintic else None
        waypoints = [[HOME[j] + i * pi / 4 for j in UPSTREAM_ORDER] for i in (0, -1, 1)]
        goal = h.goal([point(q, t, zero, zero) for q, t in zip(waypoints, (4.0, 8.0, 12.0))], names=h.names,
                      goal_tol=[(n, tolerance, 0.0, 0.0) for n in h.names], goal_time=goal_time)
        handle = h.send(goal, client=client)
        assert handle.accepted
        status, code, text = h.result(handle, timeout=60)
        assert code == expected, text
        if expected == rc.SUCCESSFUL:
            assert np.abs(h.q - np.array(waypoints[-1])[[2, 1, 0, 3, 4, 5]]).max() < 0.01


# ---- integration_test_trajectory_until.py --------------------------------------------------------------------------
UNTIL_CONFIGS = [('', SCALED), ('my_ur_', PASS)]


@pytest.mark.parametrize('driver', UNTIL_CONFIGS, indirect=True, ids=['noprefix-scaled', 'my_ur_-passthrough'])
class TestTrajectoryUntil:
    def _goal(self, h) -> Until.Goal:
        points = [point([1.5, -1.5, 0.0, -1.5, -1.5, -1.5], 3.0), point([2.1, -1.2, 0.0, -2.4, -1.5, -1.5], 6.0)]
        return Until.Goal(trajectory=h.goal(points, names=h.names).trajectory, until_type=Until.Goal.TOOL_CONTACT)

    def _send(self, h, client, goal):
        future = client.send_goal_async(goal)
        wait_still(future.done, what='the until goal answer')
        return future.result()

    def test_runs_to_its_end_without_contact_or_is_cancelled(self, robot):
        h = robot
        initial = h.sim.cfg.initial_joint_controller
        assert h.cm.states()[initial] == 'active'
        client = getattr(h, 'until', None)
        if client is None:  # made once per ur_sim: it goes with the harness's node
            client = h.until = ActionClient(h.client, Until, '/trajectory_until_node/execute',
                                            callback_group=ReentrantCallbackGroup())
            wait_still(client.server_is_ready, what='the trajectory_until action server')
        assert h.cm.switch(activate=[TOOL], strictness=BEST_EFFORT).ok
        handle = self._send(h, client, self._goal(h))
        assert handle.accepted
        future = handle.get_result_async()
        wait_for(future.done, 30.0, 'the until result')
        result = future.result().result
        assert (result.error_code, result.until_condition_result) == (Until.Result.SUCCESSFUL,
                                                                      Until.Result.NOT_TRIGGERED)
        tool = next(c for c in h.sim.components if c.name == TOOL)
        wait_still(lambda: not tool.watching, what='the tool contact goal ended with the trajectory')
        assert h.cm.switch(activate=[TOOL, initial], strictness=BEST_EFFORT).ok
        handle = self._send(h, client, self._goal(h))
        assert handle.accepted
        cancel = handle.cancel_goal_async()
        wait_still(cancel.done, what='the cancel answer')
        assert cancel.result().return_code == 0  # ERROR_NONE
        future = handle.get_result_async()
        wait_for(future.done, 30.0, 'the cancelled until result')
        assert future.result().status == GoalStatus.STATUS_CANCELED
        # Back where the test began, on the initial controller: the harness's keeper moves the arm back on the scaled
        # controller only, which cannot start beside an active passthrough controller.
        back = h.send(h.goal([point(h.keeper.pose, 4.0, each(0.0))]), client=action(h, initial))
        assert back.accepted and h.result(back)[1] == rc.SUCCESSFUL
        wait_for(lambda: np.abs(h.q - h.keeper.pose).max() < 1e-3 and np.abs(h.sim.sim.state().qd).max() < 1e-3,
                 2.0, 'the arm at rest where it began')


# ---- example_move.py: the driver's example client, two trajectories one after the other ---------------------------
EXAMPLE = [[(4.0, [0.043128, -1.28824, 1.37179, -1.82208, -1.63632, -0.18]),
            (8.0, [-0.195016, -1.70093, 0.902027, -0.944217, -1.52982, -0.195171])],
           [(0.0, [-0.195016, -1.70094, 0.902027, -0.944217, -1.52982, -0.195171]),
            (8.0, [0.30493, -0.982258, 0.955637, -1.48215, -1.72737, 0.204445])]]


class TestExampleMove:
    def test_the_examples_two_trajectories_succeed_in_turn(self, robot):
        h = robot
        for trajectory in EXAMPLE:
            goal = h.goal([point(q, t, each(0.0)) for t, q in trajectory], goal_time=0.5,
                          goal_tol=[(n, 0.01, 0.01, 0.0) for n in h.joints])
            handle = h.send(goal)
            assert handle.accepted
            assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
            assert np.abs(h.q - trajectory[-1][1]).max() < 0.01
            h.wait_sim_time(2.0)  # the example pauses between its trajectories
