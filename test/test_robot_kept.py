"""Every test leaves a working robot (conftest.py's robot_recovered): the first test here ends in a protective stop
with outputs, payload, speed slider and controllers changed; the next one, on the same simulation, finds the robot
as it was at the start, in its starting pose, and moves it."""
import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import ControllerManagerClient
from sim_harness import point, running_sim, wait_answer, wait_for, wait_still
from ur_msgs.srv import SetIO, SetPayload, SetSpeedSliderFraction

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import NORMAL, PROTECTIVE_STOP, RUNNING

START = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])


@pytest.fixture(scope='module')
def h():
    with running_sim(ur_type='ur5e', initial_positions=START.tolist()) as harness:
        yield harness


def _call(h, srv_type, name: str, request):
    client = h.client.create_client(srv_type, f'/io_and_status_controller/{name}')
    wait_still(client.service_is_ready, what=name)
    # The client is left for the harness's teardown: destroyed under its spinning executor, rclpy can kill that thread.
    return wait_answer(client.call_async(request), f'the answer of {name}')


def test_a_test_that_ends_in_a_protective_stop_with_everything_changed(h):
    assert _call(h, SetIO, 'set_io', SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=3, state=1.0)).success
    assert _call(h, SetIO, 'set_io', SetIO.Request(fun=SetIO.Request.FUN_SET_TOOL_VOLTAGE, state=24.0)).success
    assert _call(h, SetPayload, 'set_payload', SetPayload.Request(mass=1.5)).success
    assert _call(h, SetSpeedSliderFraction, 'set_speed_slider',
                 SetSpeedSliderFraction.Request(speed_slider_fraction=0.5)).success
    assert ControllerManagerClient(h).switch(activate=['forward_position_controller'],
                                             deactivate=['scaled_joint_trajectory_controller']).ok
    assert ControllerManagerClient(h).switch(activate=['scaled_joint_trajectory_controller'],
                                             deactivate=['forward_position_controller']).ok
    assert ControllerManagerClient(h).switch(activate=['tool_contact_controller']).ok
    # The wrist folded into the upper arm: a protective stop, and the test ends there.
    handle = h.send(h.goal([point(START + np.array([0.0, 0.0, 4.0, 0.0, 0.0, 0.0]), 4.0, np.zeros(6))]))
    assert handle.accepted
    assert h.result(handle)[1] == rc.INVALID_GOAL
    assert h.sim.robot.safety_mode == PROTECTIVE_STOP
    wait_for(lambda: h.sim.sim.io.tool_voltage == 24 and h.sim.sim.payload.mass == 1.5, what='the changes applied')


def test_the_next_test_finds_the_robot_as_it_was_and_moves_it(h):
    robot, sim = h.sim.robot, h.sim.sim
    assert (robot.robot_mode, robot.safety_mode, robot.program_running) == (RUNNING, NORMAL, True)
    assert not any(sim.io.digital_out) and sim.io.tool_voltage == 0
    assert sim.payload.mass == 0.0 and h.sim.scaling.slider == 1.0
    states = ControllerManagerClient(h).states()
    assert states['scaled_joint_trajectory_controller'] == 'active'
    assert states['tool_contact_controller'] == 'inactive'
    assert np.abs(h.q - START).max() < 1e-3  # moved back out of the self-collision
    away = START + np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0])
    handle = h.send(h.goal([point(away, 3.0, np.zeros(6))]))
    assert handle.accepted
    assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    assert np.abs(h.q - away).max() < 0.01
