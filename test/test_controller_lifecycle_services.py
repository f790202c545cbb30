"""The controller manager's lifecycle and hardware services over DDS: controllers unloaded, loaded, configured and
cleaned up; the hardware component taken through its states (the driver's component-lifecycle scenario) and what
that does to the simulated robot."""
from __future__ import annotations

import numpy as np
import pytest
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from lifecycle_msgs.msg import State
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
from sim_harness import point, running_sim, wait_answer, wait_for, wait_still
from std_msgs.msg import Float64MultiArray

from ur_sim_driver.controllers.ur_hardware import friction_interfaces, gravity_interfaces
from ur_sim_driver.robot.robot_state import STOPPED

SCALED, FVC = 'scaled_joint_trajectory_controller', 'forward_velocity_controller'
ZERO = [0.0] * 6
UNCONFIGURED, INACTIVE, ACTIVE = (State.PRIMARY_STATE_UNCONFIGURED, State.PRIMARY_STATE_INACTIVE,
                                  State.PRIMARY_STATE_ACTIVE)


def test_hardware_starts_unconfigured_as_the_robot_models_test_starts_it():
    """hardware_components_initial_state: the component waits unconfigured, no controller runs, the program does not
    play; configured and activated, the robot works."""
    # First: its ur_sim shares the test process's domain, so it must be gone before the module's starts.
    with running_sim(hardware_components_initial_state={'unconfigured': ['ur5e']}) as h:
        cm = ControllerManagerClient(h)
        (component,) = cm.components()
        assert (component.name, component.state.id) == ('ur5e', UNCONFIGURED)
        assert 'active' not in cm.states().values()
        assert not h.sim.robot.program_running
        response = cm.set_component_state('ur5e', INACTIVE, 'inactive')
        assert response.ok and (response.state.id, response.state.label) == (INACTIVE, 'inactive')
        assert cm.set_component_state('ur5e', ACTIVE).ok
        assert cm.switch(activate=['joint_state_broadcaster', SCALED]).ok
        assert h.keeper.call('resend_robot_program').success
        goal = h.send(h.goal([point(h.q + np.array([0.1, 0, 0, 0, 0, 0]), 1.0, ZERO)]))
        assert goal.accepted and h.result(goal)[1] == 0


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.cm = ControllerManagerClient(h)
        yield h


def _nodes(h) -> set[str]:
    return set(h.client.get_node_names())


def test_unload_and_load_a_controller(robot):
    cm = robot.cm
    assert FVC in _nodes(robot)
    assert not cm.lifecycle('unload', SCALED)  # still active
    assert cm.lifecycle('unload', FVC)
    assert FVC not in cm.states()
    wait_still(lambda: FVC not in _nodes(robot), what='the controller node gone from the graph')
    assert not cm.lifecycle('unload', FVC)  # no longer loaded
    assert cm.lifecycle('load', FVC)  # its type is the controller manager's parameter <name>.type
    assert cm.states()[FVC] == 'unconfigured'
    assert list(cm.controllers()[FVC].required_command_interfaces) == []  # known once configured
    wait_still(lambda: FVC in _nodes(robot), what='the controller node back in the graph')
    assert not cm.lifecycle('load', FVC)  # loaded twice
    response = cm.switch(activate=[FVC], deactivate=[SCALED])
    assert not response.ok and "is in 'unconfigured' state" in response.message
    assert cm.lifecycle('configure', FVC) and cm.states()[FVC] == 'inactive'
    assert cm.switch(activate=[FVC], deactivate=[SCALED]).ok
    assert not cm.lifecycle('cleanup', FVC) and not cm.lifecycle('configure', FVC)  # active
    # The reloaded controller commands the robot through its new node.
    # Left for the harness's teardown: destroyed under its spinning executor, rclpy can kill that thread.
    pub = robot.client.create_publisher(Float64MultiArray, 'forward_velocity_controller/commands', 10)
    wait_still(lambda: pub.get_subscription_count() > 0, what='the reloaded controller subscribed')
    q0 = robot.q
    pub.publish(Float64MultiArray(data=[0.1, 0, 0, 0, 0, 0]))
    wait_for(lambda: robot.q[0] - q0[0] > 0.01, what='the base joint moving under the reloaded controller')
    pub.publish(Float64MultiArray(data=ZERO))
    assert cm.switch(activate=[SCALED], deactivate=[FVC]).ok
    assert cm.lifecycle('cleanup', FVC) and cm.states()[FVC] == 'unconfigured'
    assert cm.lifecycle('configure', FVC) and cm.states()[FVC] == 'inactive'


def test_load_needs_a_type_ur_sim_has(robot):
    cm = robot.cm
    assert not cm.lifecycle('load', 'my_controller')  # no <name>.type parameter
    assert not cm.lifecycle('configure', 'my_controller') and not cm.lifecycle('cleanup', 'my_controller')
    # Left for the harness's teardown: destroyed under its spinning executor, rclpy can kill that thread.
    client = robot.client.create_client(SetParameters, 'controller_manager/set_parameters')
    wait_still(client.service_is_ready, what='the controller manager parameter service')
    param = Parameter('my_controller.type', value='velocity_controllers/JointGroupVelocityController')
    answer = wait_answer(client.call_async(SetParameters.Request(parameters=[param.to_parameter_msg()])))
    assert answer.results[0].successful
    assert not cm.lifecycle('load', 'my_controller')  # a type ur_sim has, but not under that name
    assert 'my_controller' not in cm.states()


def test_component_lifecycle_as_the_driver_tests_it(robot):
    """The driver's component-lifecycle scenario: active -> inactive -> unconfigured -> active, with the
    interfaces available except while unconfigured."""
    cm = robot.cm

    def component():
        components = cm.components()
        assert len(components) == 1
        return components[0]

    c = component()
    assert (c.name, c.type, c.plugin_name, c.class_type) == ('ur5e', 'system',
                                                             'ur_robot_driver/URPositionHardwareInterface', '')
    assert (c.state.id, c.state.label) == (ACTIVE, 'active')
    assert all(i.is_available for i in (*c.command_interfaces, *c.state_interfaces))
    claimed = {i.name for i in c.command_interfaces if i.is_claimed}
    # The scaled JTC's, the friction model's and the gravity update's
    assert claimed == {f'{j}/position' for j in robot.joints} | set(friction_interfaces('')) | \
        set(gravity_interfaces(''))
    for target, label, available in ((INACTIVE, 'inactive', True), (UNCONFIGURED, 'unconfigured', False),
                                     (ACTIVE, 'active', True)):
        response = cm.set_component_state('ur5e', target)
        assert response.ok and (response.state.id, response.state.label) == (target, label)
        c = component()
        assert c.state.id == target
        assert all(i.is_available == available for i in (*c.command_interfaces, *c.state_interfaces))
    bad = cm.set_component_state('ur20', ACTIVE)
    assert not bad.ok and bad.state.id == 0
    by_label = cm.set_component_state('ur5e', 0, 'active')  # id 0: the label names the target
    assert by_label.ok and by_label.state.label == 'active'


def test_hardware_states_act_on_the_robot(robot):
    """Inactive: no command reaches the robot, so its External Control program exits and the robot holds; a
    commanding controller cannot be activated. Unconfigured: nothing is read. Active again: the program must be
    started again, then the robot moves."""
    h, cm = robot, robot.cm
    sim = h.sim
    goal = h.send(h.goal([point(h.q + np.array([0.4, 0, 0, 0, 0, 0]), 4.0, ZERO)]))
    assert goal.accepted
    h.wait_sim_time(0.5)
    assert cm.set_component_state('ur5e', INACTIVE).ok
    assert sim.robot.program_state == STOPPED and not sim.robot.program_running
    h.result(goal)  # the controller_stopper ended it
    wait_for(lambda: cm.states()[SCALED] == 'inactive', what='the controller stopper')
    q1 = h.q
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q1).max() < 0.02  # braked and held
    # The program runs again, but the hardware does not write: commanding controllers stay off.
    assert h.keeper.call('play').success
    response = cm.switch(activate=['forward_position_controller'], deactivate=[SCALED], strictness=BEST_EFFORT)
    assert not response.ok and response.message == ('Could not switch controllers since prepare command mode switch '
                                                     'was rejected.')
    # Unconfigured: nothing is read, /joint_states repeats the values read last while the arm is displaced.
    assert cm.set_component_state('ur5e', UNCONFIGURED).ok
    h.wait_sim_time(0.05)
    read_last = h.q.copy()
    with sim._lock:
        sim.sim.physics.reset(read_last + np.array([0, 0, 0, 0, 0, 0.05]))
    assert h.q[5] - read_last[5] > 0.04  # the arm is elsewhere (the hold brings it back within 0.1 s)
    rec = h.record()
    h.wait_sim_time(0.1)
    h.stop_recording()
    assert len(rec.q) > 10 and np.abs(np.array(rec.q) - read_last).max() < 1e-12
    assert cm.set_component_state('ur5e', ACTIVE).ok
    assert not sim.robot.program_running  # cleanup disconnected the driver: the program had ended
    assert h.keeper.call('resend_robot_program').success
    # The controller_stopper's try to restore the scaled JTC when the program played was refused (the hardware did
    # not write then), and the driver's stopper does not try again: the user activates it.
    assert cm.states()[SCALED] == 'inactive'
    assert cm.switch(activate=[SCALED]).ok
    goal = h.send(h.goal([point(h.q - np.array([0.2, 0, 0, 0, 0, 0]), 2.0, ZERO)]))
    assert goal.accepted and h.result(goal)[1] == 0
