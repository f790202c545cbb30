"""The controller manager over DDS: the default set, every switch rule, the driver's own controller-switch
scenario (ur_robot_driver/test/integration_test_controller_switch.py), goals to inactive controllers and the
controller_stopper."""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, STRICT, ControllerManagerClient
from sim_harness import point, running_sim, trajectory, wait_for

from ur_sim_driver.controllers.ur_hardware import friction_interfaces, gravity_interfaces
from ur_sim_driver.motion import result_codes as rc

SCALED, JTC = 'scaled_joint_trajectory_controller', 'joint_trajectory_controller'
FPC, FVC = 'forward_position_controller', 'forward_velocity_controller'
PASS, FREE, TOOL = 'passthrough_trajectory_controller', 'freedrive_mode_controller', 'tool_contact_controller'
# The driver's test list of controllers.
FRICTION = 'friction_model_controller'
ALL_CONTROLLERS = [SCALED, JTC, FPC, FVC, PASS, 'force_mode_controller', FREE, FRICTION]
EFFORT = 'forward_effort_controller'
ZERO = [0.0] * 6


@pytest.fixture(scope='module')
def robot():
    with running_sim(tf_prefix='my_ur_') as h:
        h.cm = ControllerManagerClient(h)
        yield h


@pytest.fixture(autouse=True)
def default_controllers(robot):
    """Every test starts from the driver's defaults: the scaled JTC is the active joint controller."""
    defaults = (SCALED, FRICTION)
    robot.cm.switch(activate=defaults, deactivate=[c for c in ALL_CONTROLLERS if c not in defaults],
                    strictness=BEST_EFFORT)
    assert robot.cm.states()[SCALED] == 'active'


def _active(h) -> set[str]:
    return {name for name, state in h.cm.states().items() if state == 'active'}


def test_default_set_as_the_driver_loads_it(robot):
    controllers = robot.cm.controllers()
    states = {n: c.state for n, c in controllers.items()}
    for name in ('joint_state_broadcaster', 'speed_scaling_state_broadcaster', 'tcp_pose_broadcaster', SCALED):
        assert states[name] == 'active', name
    for name in (JTC, FPC, FVC, PASS, FREE, TOOL):
        assert states[name] == 'inactive', name
    types = {n: c.type for n, c in controllers.items()}
    assert types[SCALED] == 'ur_controllers/ScaledJointTrajectoryController'
    assert types[JTC] == 'joint_trajectory_controller/JointTrajectoryController'
    assert types[FPC] == 'position_controllers/JointGroupPositionController'
    assert types[FVC] == 'velocity_controllers/JointGroupVelocityController'
    assert types[PASS] == 'ur_controllers/PassthroughTrajectoryController'
    position = [f'{j}/position' for j in robot.joints]
    assert robot.joints[0] == 'my_ur_shoulder_pan_joint'
    assert list(controllers[SCALED].claimed_interfaces) == position
    assert list(controllers[JTC].claimed_interfaces) == [] and list(controllers[JTC].required_command_interfaces) == \
        position
    assert list(controllers[FVC].required_command_interfaces) == [f'{j}/velocity' for j in robot.joints]
    assert 'my_ur_speed_scaling/speed_scaling_factor' in controllers[SCALED].required_state_interfaces
    assert 'my_ur_freedrive_mode/enable' in controllers[FREE].required_command_interfaces
    assert all(c.update_rate == 500 and not c.is_chainable for c in controllers.values())
    types = robot.cm.types()
    assert 'velocity_controllers/JointGroupVelocityController' in types.types
    assert len(types.base_classes) == len(types.types)
    hardware = robot.cm.hardware()
    claimed = {i.name for i in hardware.command_interfaces if i.is_claimed}
    # The scaled JTC's, the friction model's and the gravity update's (active by default, as the driver spawns them).
    assert claimed == set(position) | set(friction_interfaces('my_ur_')) | set(gravity_interfaces('my_ur_'))
    assert {f'{j}/velocity' for j in robot.joints} <= {i.name for i in hardware.command_interfaces}
    assert f'{robot.joints[2]}/effort' in {i.name for i in hardware.state_interfaces}


# ---- the driver's controller-switch scenario -------------------------------------------------------------------------
def test_activating_multiple_controllers_same_interface_fails(robot):
    cm = robot.cm
    assert cm.switch(deactivate=ALL_CONTROLLERS, strictness=BEST_EFFORT).ok
    assert not cm.switch(activate=[SCALED, JTC]).ok
    assert not cm.switch(activate=[SCALED, FPC]).ok
    assert not (_active(robot) & set(ALL_CONTROLLERS))


def test_activating_multiple_controllers_different_interface_fails(robot):
    cm = robot.cm
    assert cm.switch(deactivate=ALL_CONTROLLERS, strictness=BEST_EFFORT).ok
    for pair in ([SCALED, FVC], [SCALED, PASS], [FVC, PASS], [FPC, FVC], [SCALED, FREE]):
        response = cm.switch(activate=pair)
        assert not response.ok, pair
    # The UR hardware's refusal ('Starting velocity together with position is not allowed.') is logged; the answer
    # is the controller manager's.
    assert cm.switch(activate=[FPC, FVC]).message == ('Could not switch controllers since prepare command mode '
                                                      'switch was rejected.')
    assert not (_active(robot) & set(ALL_CONTROLLERS))


def test_activating_controller_with_running_position_controller_fails(robot):
    cm = robot.cm
    assert cm.switch(activate=[SCALED], deactivate=[c for c in ALL_CONTROLLERS if c != SCALED],
                     strictness=BEST_EFFORT).ok
    for name in (FPC, FVC, EFFORT, FREE, PASS, 'force_mode_controller'):
        assert not cm.switch(activate=[name]).ok, name
    conflict = cm.switch(activate=[FPC], strictness=BEST_EFFORT)  # refused whatever the strictness
    assert not conflict.ok and conflict.message == (
        "Unable to activate controller 'forward_position_controller' since the command interface "
        f"'{robot.joints[0]}/position' is currently claimed by another controller.")
    assert cm.switch(deactivate=[SCALED]).ok
    assert cm.states()[SCALED] == 'inactive'


# ---- the rules -------------------------------------------------------------------------------------------------------
def test_strict_fails_as_a_whole_and_best_effort_does_the_possible_part(robot):
    cm = robot.cm
    response = cm.switch(activate=[FPC, 'no_such_controller'], deactivate=[SCALED], strictness=STRICT)
    assert not response.ok and 'no controller with this name exists' in response.message
    assert cm.states()[SCALED] == 'active' and cm.states()[FPC] == 'inactive'
    response = cm.switch(activate=[FPC, 'no_such_controller'], deactivate=[SCALED], strictness=BEST_EFFORT)
    assert response.ok
    assert cm.states()[SCALED] == 'inactive' and cm.states()[FPC] == 'active'
    # Already active / not active: STRICT refuses, BEST_EFFORT does nothing and succeeds.
    assert not cm.switch(activate=[FPC]).ok
    assert not cm.switch(deactivate=[JTC]).ok
    assert cm.switch(activate=[FPC], deactivate=[JTC], strictness=BEST_EFFORT).ok
    assert cm.states()[FPC] == 'active'
    # Two claimants of one interface fail the request whatever the strictness: nothing is switched.
    response = cm.switch(activate=[JTC, SCALED], deactivate=[FPC], strictness=BEST_EFFORT)
    assert not response.ok and 'will be used by another controller that is being activated' in response.message
    states = cm.states()
    assert states[JTC] == 'inactive' and states[SCALED] == 'inactive' and states[FPC] == 'active'


def test_tool_contact_runs_beside_the_joint_controller_and_freedrive_alone(robot):
    cm = robot.cm
    assert cm.switch(activate=[TOOL]).ok  # its own interface only: no conflict with the scaled JTC
    assert _active(robot) >= {SCALED, TOOL}
    assert list(cm.controllers()[TOOL].claimed_interfaces) == ['my_ur_tool_contact/tool_contact_set_state']
    refused = cm.switch(activate=[FREE], deactivate=[SCALED])  # freedrive does not run beside tool contact
    assert not refused.ok and cm.states()[FREE] == 'inactive'
    assert cm.switch(activate=[FREE], deactivate=[SCALED, TOOL]).ok
    assert cm.states()[FREE] == 'active'
    assert cm.switch(activate=[SCALED], deactivate=[FREE]).ok


def test_effort_is_loaded_and_the_hardware_refuses_it_beside_the_position_controller(robot):
    cm = robot.cm
    controllers = cm.controllers()
    assert controllers[EFFORT].type == 'effort_controllers/JointGroupEffortController'
    assert controllers[EFFORT].state == 'inactive'
    assert list(controllers[EFFORT].required_command_interfaces) == [f'{j}/effort' for j in robot.joints]
    for strictness in (STRICT, BEST_EFFORT):  # torque control runs alone (robot software 5.25.1 has it)
        response = cm.switch(activate=[EFFORT], strictness=strictness)
        assert (response.ok, response.message) == (False, 'Could not switch controllers since prepare command mode '
                                                          'switch was rejected.')
    assert cm.states()[SCALED] == 'active' and cm.states()[EFFORT] == 'inactive'


def test_strictness_and_timeout_fields(robot):
    cm = robot.cm
    assert cm.switch(activate=[JTC], deactivate=[SCALED], strictness=0, timeout=5.0).ok  # 0: BEST_EFFORT
    assert cm.states()[JTC] == 'active'
    bad = cm.switch(activate=[SCALED], deactivate=[JTC], strictness=9)
    assert not bad.ok and 'strictness = 9' in bad.message and cm.states()[JTC] == 'active'


# ---- what the controllers do when switched ---------------------------------------------------------------------------
def test_goals_and_messages_to_an_inactive_controller_are_refused(robot):
    h = robot
    q0 = h.q
    handle = h.send(h.goal([point(q0 + 0.1, 1.0, ZERO)]))  # the scaled JTC takes goals by default
    assert handle.accepted and h.result(handle)[1] == rc.SUCCESSFUL
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    assert not h.send(h.goal([point(h.q + 0.1, 1.0, ZERO)])).accepted
    q1 = h.q
    h.topic.publish(trajectory(h.joints, [point(q1 + 0.2, 0.5, ZERO)]))
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q1).max() < 1e-3


def test_switching_away_ends_the_running_goal_and_holds(robot):
    h = robot
    handle = h.send(h.goal([point(h.q + np.array([0.5, 0, 0, 0, 0, 0]), 3.0, ZERO)]))
    assert handle.accepted
    h.wait_sim_time(0.5)
    assert h.cm.switch(activate=[JTC], deactivate=[SCALED]).ok
    status, code, text = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL) and 'deactivate' in text
    q1 = h.q
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q1).max() < 0.02  # it stopped where it was (after braking)


def test_controller_stopper_deactivates_and_restores_the_joint_controller(robot):
    h = robot
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    with h.sim._lock:
        assert h.sim.robot.pause() is None
    wait_for(lambda: h.cm.states()[FPC] == 'inactive', what='the stopper to deactivate the forward controller')
    assert h.cm.states()['joint_state_broadcaster'] == 'active'
    with h.sim._lock:
        assert h.sim.robot.play() is None
    wait_for(lambda: h.cm.states()[FPC] == 'active', what='the stopper to restore the forward controller')
    assert h.cm.states()[SCALED] == 'inactive'
