"""/ur_robot_state_helper/set_mode over DDS: targets reached from power off and from running, the program played or
stopped, the safety recovered, refused targets, and cancel refused (the driver's robot_state_helper)."""
from __future__ import annotations

import pytest
from action_msgs.srv import CancelGoal
from sim_harness import running_sim, wait_answer, wait_for, wait_still
from ur_dashboard_msgs.action import SetMode

from ur_common.action_client import ActionClient  # rclpy's loses a fast goal response
from ur_sim_driver.robot.robot_state import IDLE, NORMAL, POWER_OFF, POWER_ON, RUNNING

REACHED = 'Reached target robot mode.'


@pytest.fixture(scope='module')
def robot():
    with running_sim(start_powered_off=True) as h:
        h.set_mode = ActionClient(h.client, SetMode, '/ur_robot_state_helper/set_mode')
        wait_still(h.set_mode.server_is_ready, what='the set_mode action server')
        # Not destroyed here: the harness's executor still spins the client node, and an action client destroyed
        # under it kills the spin thread (RCLError: action client pointer is invalid, seen in a CI run); it goes
        # with its node once the harness has stopped spinning.
        yield h


def _run(h, target, stop_program=False, play_program=False, feedback=None):
    """Send a goal and wait for its result: (status, success, message)."""
    goal = SetMode.Goal(target_robot_mode=target, stop_program=stop_program, play_program=play_program)
    handle = wait_answer(h.set_mode.send_goal_async(goal, feedback_callback=feedback), 'the goal answer')
    assert handle.accepted
    result = wait_answer(handle.get_result_async(), 'the set_mode result')
    return result.status, result.result.success, result.result.message


def test_from_power_off_to_running_playing_the_program(robot):
    h = robot
    assert h.sim.robot.robot_mode == POWER_OFF and not h.sim.robot.program_running
    modes = []
    status, success, message = _run(h, RUNNING, play_program=True,
                                    feedback=lambda f: modes.append(f.feedback.current_robot_mode))
    assert (success, message) == (True, REACHED)
    assert h.sim.robot.robot_mode == RUNNING and h.sim.robot.program_running  # headless: the program was sent
    wait_for(lambda: modes and modes[-1] == RUNNING, what='the last feedback')
    assert modes[0] in (POWER_OFF, POWER_ON) and RUNNING in modes


def test_idle_from_running_powers_off_and_on(robot):
    h = robot
    h.keeper.recover()  # running, program playing
    status, success, message = _run(h, IDLE, stop_program=True)
    assert (success, message) == (True, REACHED)
    assert h.sim.robot.robot_mode == IDLE and not h.sim.robot.program_running


def test_protective_stop_is_unlocked_once_allowed(robot):
    h = robot
    h.keeper.recover()
    with h.sim._lock:
        h.sim.robot.protective_stop(h.sim.sim.time, 'test')
    # Within the robot's 5 s the unlock is refused, so the transition fails.
    assert _run(h, RUNNING)[1:] == (False, 'Transition to target mode failed.')
    wait_for(lambda: h.sim.robot.unlock_wait() == 0.0, what='the 5 s before an unlock')
    assert _run(h, RUNNING)[1:] == (True, REACHED)
    assert h.sim.robot.safety_mode == NORMAL


@pytest.mark.parametrize(('target', 'message'), [
    (POWER_ON, 'Requested target mode POWER_ON which cannot be explicitly selected.'),
    (42, 'Requested illegal mode.'),
])
def test_refused_targets(robot, target, message):
    mode = robot.sim.robot.robot_mode
    assert _run(robot, target)[1:] == (False, message)
    assert robot.sim.robot.robot_mode == mode


def test_cancel_is_refused(robot):
    h = robot
    h.keeper.recover()
    # IDLE from RUNNING: power off and on, then 0.5 s of simulated time until IDLE. The simulation is held still
    # until the cancel is answered, so the goal is still running then.
    future = h.set_mode.send_goal_async(SetMode.Goal(target_robot_mode=IDLE))
    wait_still(future.done, what='the goal answer')
    handle = future.result()
    cancel_future = handle.cancel_goal_async()
    wait_still(cancel_future.done, what='the cancel answer')
    cancel = cancel_future.result()
    # Refused: no goal is canceling (rclpy answers a refusal with ERROR_NONE and an empty list, rclcpp with
    # ERROR_REJECTED; the list is what both agree on).
    assert cancel.return_code in (CancelGoal.Response.ERROR_NONE, CancelGoal.Response.ERROR_REJECTED)
    assert list(cancel.goals_canceling) == []
    result = wait_answer(handle.get_result_async(), 'the set_mode result')
    assert result.result.success and h.sim.robot.robot_mode == IDLE
