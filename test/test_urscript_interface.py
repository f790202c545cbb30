"""/urscript_interface over DDS, as the driver's (its own integration test's cases in our words): the script topic
runs a statement and a sec program (IO on io_states), the SendScript action succeeds, refuses a second goal while
one runs, is cancelled and is ready again, reports a runtime error with the program's lines, refuses a robot that
is not running, and a movej it sends moves the arm (the External Control program stops, as on the robot)."""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import running_sim, wait_answer, wait_for, wait_still
from std_msgs.msg import String
from ur_msgs.action import SendScript
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

from ur_common.action_client import ActionClient  # rclpy's loses a fast goal response
from ur_sim_driver.robot.robot_state import POWER_OFF, RUNNING
from ur_sim_driver.urscript.runner import STOPPED

SCRIPT = '/urscript_interface/execute_script'


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.script = ActionClient(h.client, SendScript, SCRIPT, callback_group=ReentrantCallbackGroup())
        h.topic_pub = h.client.create_publisher(String, '/urscript_interface/script_command', 1)
        wait_still(h.script.server_is_ready, what='the SendScript action server')
        wait_still(lambda: h.topic_pub.get_subscription_count() > 0, what='the script_command subscriber')
        h.script_events = []
        undo = h.sim.host.scripts.listen(h.script_events.append)  # from the simulation loop
        try:
            yield h
        finally:
            undo()



def _goal(program: str, name: str = '') -> SendScript.Goal:
    return SendScript.Goal(program=program, script_name=name, start_timeout=Duration(sec=10),
                            fail_on_warnings=False)


def _send(h, goal):
    future = h.script.send_goal_async(goal)
    return wait_answer(future, what='the SendScript goal answer')


def _result(h, handle, name: str):
    """The goal's result: held still until its program `name` was submitted (the action's execution starts it,
    after the goal was accepted), stepping until it has stopped, then held still for the result's delivery."""
    def stopped() -> bool:
        return any(e.kind == STOPPED and e.name == name for e in list(h.script_events))
    future = handle.get_result_async()
    wait_still(lambda: stopped() or (h.sim.host.scripts.current is not None
                                     and h.sim.host.scripts.current.name == name), what=f'program {name} started')
    wait_for(stopped, what=f'program {name} to stop')
    wait_still(future.done, what='the SendScript result')
    return future.result()


def test_the_topic_runs_a_statement_and_a_secondary_program(robot):
    h = robot
    states: list[IOStates] = []
    stop = h.listen(IOStates, '/io_and_status_controller/io_states', states.append, depth=10)
    try:
        assert h.sim.robot.program_running
        h.topic_pub.publish(String(data='set_digital_out(0, True)'))
        wait_still(lambda: h.sim.host.scripts.current is not None or h.sim.sim.io.digital_out[0],
                   what='the script at ur_sim')
        wait_for(lambda: h.sim.sim.io.digital_out[0] and h.sim.host.scripts.current is None, what='the program')
        assert not h.sim.robot.program_running  # a program replaced External Control, as on the robot
        h.topic_pub.publish(String(data='sec my_program():\n  set_digital_out(0, False)\n  set_digital_out(1,True)\n'
                                        'end'))
        wait_still(lambda: h.sim.sim.io.digital_out[1], what='the sec program')  # runs as it arrives
        assert not h.sim.sim.io.digital_out[0]
        states.clear()
        wait_for(lambda: states and [s.state for s in states[-1].digital_out_states[:2]] == [False, True],
                 what='io_states showing the outputs')
    finally:
        stop()
        client = h.client.create_client(SetIO, '/io_and_status_controller/set_io')
        for pin in (0, 1):
            wait_answer(client.call_async(SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=pin, state=0.0)))
        # The client is left for the harness's teardown: destroyed under the spinning executor, rclpy can kill it.


def test_a_script_runs_to_its_end_and_is_ready_again_after_a_cancel(robot):
    h = robot
    log = h.rosout()
    handle = _send(h, _goal('textmsg("hello")', 'test_send_script_action'))
    assert handle.accepted
    result = _result(h, handle, 'test_send_script_action')
    assert (result.status, result.result.success) == (GoalStatus.STATUS_SUCCEEDED, True)
    assert result.result.message == 'Script executed successfully'
    wait_still(lambda: any(m == 'textmsg: hello' for _, m in log), what='the text message in the log')

    long = _send(h, _goal('sleep(5.)', 'test_reject_goals'))
    assert long.accepted
    wait_still(lambda: h.sim.host.scripts.current is not None, what='the sleeping program started')
    h.wait_sim_time(0.5)
    assert not _send(h, _goal('textmsg("Should be rejected")')).accepted  # busy
    cancel = long.cancel_goal_async()
    wait_still(cancel.done, what='the cancel answer')
    assert cancel.result().return_code == 0
    result = _result(h, long, 'test_reject_goals')
    assert result.status == GoalStatus.STATUS_CANCELED and not result.result.success
    assert result.result.message == 'Script execution canceled'
    again = _send(h, _goal('textmsg("again")', 'again'))
    assert again.accepted and _result(h, again, 'again').result.success


def test_a_runtime_error_aborts_the_goal_with_the_programs_lines(robot):
    h = robot
    q0 = h.q
    handle = _send(h, _goal('x = 1\nmovej([0, 0, 0])', 'bad_move'))
    result = _result(h, handle, 'bad_move')
    assert result.status == GoalStatus.STATUS_ABORTED and not result.result.success
    message = result.result.message
    assert message.startswith('Runtime exception occured during script execution.Runtime exception type: ')
    assert 'movej: q is a list of 6 joint values' in message and 'Exception occured at line 3' in message
    assert '1: def bad_move():\n2:   x = 1\n3:   movej([0, 0, 0])\n' in message and '^<--- here' in message
    assert np.abs(h.q - q0).max() < 1e-3


def test_a_syntax_error_is_refused_and_nothing_runs(robot):
    h = robot
    handle = _send(h, _goal('movej([0, 0, 0, 0, 0, 0]', 'unclosed'))
    future = handle.get_result_async()
    wait_still(future.done, what='the SendScript result')
    result = future.result()
    assert result.status == GoalStatus.STATUS_ABORTED
    # line breaks carry no meaning: the call is still open when 'end' comes
    assert "syntax error on line 3, column 1: unexpected 'end'" in result.result.message
    assert h.sim.robot.program_running


def test_a_robot_that_is_not_running_is_refused(robot):
    h = robot
    assert h.keeper.call('power_off').success
    wait_for(lambda: h.sim.robot.robot_mode == POWER_OFF, what='power off')
    handle = _send(h, _goal('textmsg("x")'))
    future = handle.get_result_async()
    wait_still(future.done, what='the SendScript result')
    result = future.result()
    assert result.status == GoalStatus.STATUS_ABORTED
    assert result.result.message == ('Robot is in incorrect mode for the requested operation: Script execution via '
                                     'primary interface\nRequired robot mode: RUNNING (7) \nActual robot mode: '
                                     'POWER_OFF (3)')
    assert h.sim.robot.robot_mode == POWER_OFF != RUNNING


def test_a_movej_moves_the_arm_and_ends_when_it_arrives(robot):
    h = robot
    target = h.q + np.array([0.3, 0.0, 0.0, 0.0, 0.0, -0.3])
    handle = _send(h, _goal(f'movej({[float(v) for v in target]}, a=1.4, v=1.05)', 'move_it'))
    assert handle.accepted
    assert _result(h, handle, 'move_it').result.success
    assert np.abs(h.q - target).max() < 2e-3
    assert not h.sim.robot.program_running  # the driver resends its program to move again (the keeper does)
