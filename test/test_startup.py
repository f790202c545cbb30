"""What the driver's launch file starts (controllers/startup.py): the initial joint controller, its refusals, and no
controller with a hardware component that does not start active."""
from __future__ import annotations

import pytest

from ur_sim_driver.controllers import startup
from ur_sim_driver.controllers.forward_command import ForwardCommandController
from ur_sim_driver.controllers.joint_state_broadcaster import JointStateBroadcaster
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.software import SoftwareVersion
from ur_sim_driver.ros.dashboard import DashboardClient


def _components():
    return [JointStateBroadcaster(), ForwardCommandController('position'), ForwardCommandController('velocity'),
            DashboardClient()]


def test_initial_joint_controller():
    cfg = SimConfig(initial_joint_controller='forward_velocity_controller')
    assert startup.initial_joint_controller(cfg) == 'forward_velocity_controller'
    components = _components()
    assert startup.set_start_states(cfg, 'forward_velocity_controller', components) is None
    assert [c.initially_active for c in components] == [True, False, True, True]
    renamed = SimConfig(controller_name='vel_based_pos_traj_controller')
    assert startup.initial_joint_controller(renamed) == 'vel_based_pos_traj_controller'
    assert startup.initial_joint_controller(SimConfig(activate_joint_controller=False)) is None


def test_refusals_name_the_choices():
    with pytest.raises(ConfigError, match='valid choices: scaled_joint_trajectory_controller, joint_trajectory'):
        startup.initial_joint_controller(SimConfig(initial_joint_controller='nope'))
    old = SimConfig(initial_joint_controller='forward_effort_controller', software_version=SoftwareVersion(5, 12, 6))
    with pytest.raises(ConfigError, match='cannot be activated: Requested to use effort interface'):
        startup.initial_joint_controller(old)
    # Torque control from 5.23.0 on (the UR5e's default 5.25.1 has it).
    torque = SimConfig(initial_joint_controller='forward_effort_controller')
    assert startup.initial_joint_controller(torque) == 'forward_effort_controller'


def test_hardware_not_active_starts_no_controller():
    cfg = SimConfig(hardware_components_initial_state='inactive')
    components = _components()
    warning = startup.set_start_states(cfg, 'forward_position_controller', components)
    assert "hardware component 'ur5e' starts inactive" in warning
    # Controllers stay inactive; the dashboard client is a node, not a controller.
    assert [c.initially_active for c in components] == [False, False, False, True]
