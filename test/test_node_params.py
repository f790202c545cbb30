"""ur_sim parameters: presets, names on the graph, invalid values stop start-up with a clear message."""
import os
import subprocess
import sys
import threading

import numpy as np
import pytest
from rclpy.parameter import Parameter
from ros_helpers import ros_context
from sim_harness import point, running_sim, wait_for

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.ros.node import UrSimNode


def test_seed_ur10_preset_names_exist():
    import yaml

    from ur_sim_driver.description.scene import config_dir
    preset = yaml.safe_load((config_dir() / 'seed_ur10.yaml').read_text())['/**']['ros__parameters']
    with running_sim(**preset) as h:
        assert h.sim.sim.params.name.lower() == 'ur10'
        topics = dict()
        wait_for(lambda: topics.update(h.client.get_topic_names_and_types()) or
                 '/ur10/joint_states' in topics, what='/ur10/joint_states')
        assert 'sensor_msgs/msg/JointState' in topics['/ur10/joint_states']
        assert '/ur10/vel_based_pos_traj_controller/joint_trajectory' in topics
        assert h.action.server_is_ready()
        assert h.action._action_name == '/ur10/vel_based_pos_traj_controller/follow_joint_trajectory'


@pytest.mark.parametrize(('name', 'value', 'expected'), [
    ('ur_type', 'ur6', "'ur_type' = 'ur6' is invalid; valid choices: ur3, ur3e, ur5, ur5e, ur7e, ur8long, ur10, "
                       'ur10e, ur12e, ur15, ur16e, ur18, ur20, ur30'),
    ('real_time_factor', -1.0, "'real_time_factor' = -1.0 is outside the allowed range [0.0, 100.0]"),
    ('speed_scaling.initial_scaling_factor', -0.5, "'speed_scaling.initial_scaling_factor' = -0.5 is outside"),
    ('tool', 'gripper', "'tool' = 'gripper' is invalid; valid choices: none, dispenser"),
    ('initial_positions', [0.0, 0.0, 4.0, 0.0, 0.0, 0.0], "'initial_positions' [2] = 4.0 rad is outside"),
    ('thread_priority', 120, "'thread_priority' = 120 must be an integer in [0, 99]"),
    ('initial_joint_controller', 'io_and_status_controller',
     "'initial_joint_controller' = 'io_and_status_controller' is not a joint controller of ur_sim; valid choices: "
     'scaled_joint_trajectory_controller, joint_trajectory_controller, forward_velocity_controller'),
    ('hardware_components_initial_state.unconfigured', ['ur20'],
     "'hardware_components_initial_state.unconfigured' = ['ur20'] names an unknown hardware component 'ur20'; valid: "
     'ur5e (the component is named after ur_type)'),
    ('use_tool_communication', True, "'use_tool_communication' = True: the tool's serial (RS-485) bridge is not "
                                     'simulated; valid: false'),
])
def test_invalid_parameter_names_parameter_value_and_range(name, value, expected):
    with ros_context() as ctx:
        try:
            node = UrSimNode(context=ctx, parameter_overrides=[Parameter(name, value=value)], start=False)
        except ConfigError as err:
            assert expected in str(err)
            return
        node.shutdown()  # started after all: shut down, so that no ur_sim is left in this process's domain
        node.destroy_node()
        pytest.fail(f'{name} = {value!r} was accepted; expected ConfigError containing {expected!r}')


def test_effort_as_initial_controller_needs_torque_control():
    with ros_context() as ctx:
        with pytest.raises(ConfigError) as err:
            UrSimNode(context=ctx, start=False, parameter_overrides=[
                Parameter('initial_joint_controller', value='forward_effort_controller'),
                Parameter('software_version', value='5.12.6')])
    assert str(err.value).startswith(
        "parameter 'initial_joint_controller' = 'forward_effort_controller' cannot be activated: Requested to use "
        "effort interface on a robot version that doesn't support it. Torque control is available from robot "
        'software 5.23.0 / 10.10.0 on.; valid choices: scaled_joint_trajectory_controller')
    # The default software (5.25.1) has torque control: the robot starts under it.
    with running_sim(initial_joint_controller='forward_effort_controller') as h:
        states = {c.name: c.active for c in h.sim.components if c.is_controller}
        assert states['forward_effort_controller'] and not states['scaled_joint_trajectory_controller']


def _fifo_permitted() -> bool:
    """Whether this process may put a thread under SCHED_FIFO (root, or an rtprio limit)."""
    result = []

    def probe() -> None:
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
            result.append(True)
        except OSError:
            result.append(False)
    thread = threading.Thread(target=probe)
    thread.start()
    thread.join()
    return result[0]


@pytest.mark.parametrize(('rtf', 'priority'), [(1.0, 10), (0.0, 10), (1.0, 0)])
def test_real_time_loop_runs_under_sched_fifo_where_permitted(rtf, priority):
    with ros_context() as ctx:
        node = UrSimNode(context=ctx, parameter_overrides=[Parameter('real_time_factor', value=rtf),
                                                           Parameter('thread_priority', value=priority)])
        try:
            t0 = node.sim.time
            wait_for(lambda: node.sim.time > t0 + 0.05, what='the simulation loop running')
            tid = node.loop.native_id
            policy, param = os.sched_getscheduler(tid), os.sched_getparam(tid)
        finally:
            node.shutdown()
            node.destroy_node()
    if rtf > 0 and priority > 0 and _fifo_permitted():
        assert (policy, param.sched_priority) == (os.SCHED_FIFO, priority)
    else:  # as fast as possible, disabled, or not permitted: normal scheduling, and the loop runs all the same
        assert policy == os.SCHED_OTHER


@pytest.mark.parametrize('args, message', [
    (['ur_type:=ur6'], "'ur_type' = 'ur6' is invalid"),
    # ros2_control_node ends when the hardware cannot reach its initial state: the driver refuses the robot model
    (['ur_type:=ur20', 'simulated_ur_type:=ur5e'], "The connected robot is of type 'UR5' and version 5.25.1-0 but "
                                                  "the driver was configured for type 'ur20'")])
def test_console_script_exits_nonzero_with_message_on_bad_parameter(args, message):
    ros_args = [a for arg in args for a in ('-p', arg)]
    proc = subprocess.run([sys.executable, '-m', 'ur_sim_driver.ros.main', '--ros-args', *ros_args],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert message in proc.stderr


def test_viewer_without_display_runs_headless(monkeypatch):
    monkeypatch.delenv('DISPLAY', raising=False)
    monkeypatch.delenv('WAYLAND_DISPLAY', raising=False)
    with running_sim(viewer=True) as h:
        t0 = h.sim.sim.time
        h.wait_sim_time(0.1)
        assert h.sim.sim.time > t0


# ---- the driver's launch arguments (ur_control.launch.py) ------------------------------------------------------------
def _active(h) -> set[str]:
    return {name for name, state in h.keeper.cm.states().items() if state == 'active'}


def test_initial_joint_controller_is_the_active_one():
    with running_sim(initial_joint_controller='forward_velocity_controller') as h:
        active = _active(h)
        assert 'forward_velocity_controller' in active and 'scaled_joint_trajectory_controller' not in active
        assert {'joint_state_broadcaster', 'io_and_status_controller'} <= active


def test_no_joint_controller_active_holds_the_robot():
    with running_sim(activate_joint_controller=False, initial_joint_controller='no_such_controller') as h:
        # Not activated, the name is not checked (the launch file only removes it from the inactive list when
        # activating it).
        active = _active(h)
        assert not active & {'scaled_joint_trajectory_controller', 'joint_trajectory_controller',
                              'forward_position_controller', 'forward_velocity_controller'}
        q0 = h.q.copy()
        h.wait_sim_time(0.5)
        assert abs(h.q - q0).max() < 1e-3
        assert not h.send(h.goal([point(q0 + 0.1, 1.0, [0.0] * 6)])).accepted


def test_without_the_dashboard_client():
    with ros_context() as ctx:
        sim = UrSimNode(context=ctx, parameter_overrides=[Parameter('launch_dashboard_client', value=False)],
                        start=False)
        try:
            names = {node.get_name() for node in sim.nodes()}
            assert 'dashboard_client' not in names and 'io_and_status_controller' in names
        finally:
            sim.shutdown()
            sim.destroy_node()


def test_resend_robot_program_needs_headless_mode():
    with running_sim(headless_mode=False) as h:
        answer = h.keeper.call('resend_robot_program')
        assert not answer.success
        assert answer.message == 'Tried to send robot program directly while not in headless mode'
        # Without headless mode the External Control program is started on the robot.
        with h.sim._lock:
            h.sim.robot.stop()  # the program stopped on the robot (a user at the pendant)
        assert h.keeper.call('play').success
        wait_for(lambda: h.sim.robot.program_running, what='the External Control program playing')


def test_unknown_parameters_are_named_and_grouped_ones_are_known():
    from ur_sim_driver.robot.sim_config import PARAMETER_NAMES, unknown_parameters
    known = ['ur_type', 'speed_scaling.initial_scaling_factor', 'dashboard_server.port', 'dashboard_server.host',
             'rtde.port', 'constraints.goal_time', 'mounted_payload.mass', 'use_sim_time']
    assert unknown_parameters(known) == []
    assert unknown_parameters(['ur_tpye', 'dashboard.port', 'speed_scaling_initial_factor']) == [
        'ur_tpye', 'dashboard.port', 'speed_scaling_initial_factor']
    assert 'dashboard_server.*' in PARAMETER_NAMES and 'dashboard_server_port' not in PARAMETER_NAMES


def test_the_default_start_is_the_descriptions_initial_pose_running():
    """The arm starts where ur_description's config/initial_positions.yaml puts the driver's mock hardware (0, -1.57,
    0, -1.57, 0, 0), RUNNING and NORMAL with External Control playing (start_powered_off: as URSim boots, powered off
    with the program stopped)."""
    from ur_sim_driver.robot.robot_state import NORMAL, PLAYING, POWER_OFF, RUNNING, STOPPED
    with ros_context() as ctx:
        node = UrSimNode(context=ctx, start=False)
        try:
            assert np.allclose(node.sim.state().q, [0.0, -1.57, 0.0, -1.57, 0.0, 0.0], atol=1e-9)
            assert (node.robot.robot_mode, node.robot.safety_mode, node.robot.program_state) == (RUNNING, NORMAL,
                                                                                               PLAYING)
        finally:
            node.shutdown()
            node.destroy_node()
    with ros_context() as ctx:
        node = UrSimNode(context=ctx, start=False, parameter_overrides=[Parameter('start_powered_off', value=True)])
        try:
            assert (node.robot.robot_mode, node.robot.program_state) == (POWER_OFF, STOPPED)
        finally:
            node.shutdown()
            node.destroy_node()
