"""Every UR type the driver supports: what each robot reports, its arm under control, and the driver's robot-model
check (``verify_robot_model``) between the configured type and the simulated robot, in plain Python and over DDS."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from cm_helpers import ControllerManagerClient
from lifecycle_msgs.msg import State
from sim_harness import point, running_sim

from ur_sim_driver.controllers import startup
from ur_sim_driver.controllers.ur_hardware import robot_model_refusal
from ur_sim_driver.description.params import UR_TYPES, load_ur_params
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.robot.software import SoftwareVersion, parse_version

# The Universal Robots Client Library's robot type and series of each ur_type (hardware_interface.cpp
# robotTypeFromString, datatypes.h robotTypeString), typed in here independently of the parameter files.
REPORTED = {'ur3': ('UR3', 'cb3'), 'ur3e': ('UR3', 'e'), 'ur5': ('UR5', 'cb3'), 'ur5e': ('UR5', 'e'),
            'ur7e': ('UR5', 'e'), 'ur8long': ('UR8_LONG', 'ur'), 'ur10': ('UR10', 'cb3'), 'ur10e': ('UR10', 'e'),
            'ur12e': ('UR10', 'e'), 'ur15': ('UR15', 'ur'), 'ur16e': ('UR16', 'e'), 'ur18': ('UR18', 'ur'),
            'ur20': ('UR20', 'ur'), 'ur30': ('UR30', 'ur')}
UNCONFIGURED, INACTIVE, ACTIVE = (State.PRIMARY_STATE_UNCONFIGURED, State.PRIMARY_STATE_INACTIVE,
                                  State.PRIMARY_STATE_ACTIVE)
ZERO = [0.0] * 6


def test_the_fourteen_types_of_the_driver():
    assert set(UR_TYPES) == set(REPORTED) and len(UR_TYPES) == 14


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_each_type_reports_as_the_client_library_expects(ur_type):
    p = load_ur_params(ur_type)
    assert (p.model, p.series) == REPORTED[ur_type]
    assert p.control_rate == (125.0 if p.series == 'cb3' else 500.0)
    assert p.payload > 0 and p.reach > 0
    minimum, default = SoftwareVersion(*p.software_minimum), SoftwareVersion(*p.software_default)
    assert minimum <= default and default.major == (3 if p.series == 'cb3' else 5)
    assert parse_version('', ur_type) == default


@pytest.mark.parametrize('ur_type', [t for t in UR_TYPES if load_ur_params(t).software_minimum > (5, 0, 0)])
def test_a_release_older_than_the_type_is_refused_naming_the_first_one(ur_type):
    first = load_ur_params(ur_type).software_minimum
    older = f'{first[0]}.{first[1] - 1}.0' if first[1] else '5.0.0'
    with pytest.raises(ConfigError) as info:
        parse_version(older, ur_type)
    text = str(info.value)
    assert "parameter 'software_version'" in text and f'does not run on a {ur_type}' in text
    assert '.'.join(map(str, first)) in text


@pytest.mark.parametrize('configured, robot, accepted', [
    ('ur5e', 'ur5e', True), ('ur7e', 'ur5e', True), ('ur5e', 'ur7e', True), ('ur12e', 'ur10e', True),
    ('ur20', 'ur5e', False), ('ur3', 'ur3e', False), ('ur10', 'ur10e', False), ('ur8long', 'ur20', False)])
def test_the_robot_model_check_compares_reported_type_and_series(configured, robot, accepted):
    """A ur7e reports as a UR5 of the e-Series: the driver cannot tell it from a ur5e, and does not."""
    version = SoftwareVersion(*load_ur_params(robot).software_default)
    reason = robot_model_refusal(configured, robot, version)
    if accepted:
        assert reason is None
    else:
        assert reason == (f"The connected robot is of type '{REPORTED[robot][0]}' and version {version} but the "
                          f"driver was configured for type '{configured}'. Please check the 'ur_type' parameter and "
                          'make sure it matches your actual robot. This can lead to critical inaccuracies of tcp '
                          'positions.')


def test_the_simulated_robot_is_the_configured_one_unless_told():
    cfg = sim_config_from_params({'ur_type': 'ur20'})
    assert cfg.simulated_ur_type == 'ur20' and cfg.verify_robot_model
    assert cfg.software_version == SoftwareVersion(*load_ur_params('ur20').software_default)
    other = sim_config_from_params({'ur_type': 'ur20', 'simulated_ur_type': 'ur5e'})
    assert other.simulated_ur_type == 'ur5e' and other.software_version == parse_version('', 'ur5e')
    with pytest.raises(ConfigError) as info:
        sim_config_from_params({'simulated_ur_type': 'ur6'})
    assert "parameter 'simulated_ur_type' = 'ur6'" in str(info.value) and 'ur8long' in str(info.value)


def test_a_mismatch_stops_the_start_as_ros2_control_node_does_unless_left_unconfigured_or_not_verified():
    cfg = sim_config_from_params({'ur_type': 'ur20', 'simulated_ur_type': 'ur5e'})
    with pytest.raises(ConfigError) as info:
        startup.check_start(cfg)
    assert "type 'UR5'" in str(info.value)
    assert 'Failed to set the initial state of the component : ur20 to active' in str(info.value)
    startup.check_start(dataclasses.replace(cfg, hardware_components_initial_state='unconfigured'))
    startup.check_start(dataclasses.replace(cfg, verify_robot_model=False))
    assert startup.configure_refusal(dataclasses.replace(cfg, verify_robot_model=False)) is None


@pytest.mark.timeout(120)
@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_each_arm_holds_and_moves_within_its_velocity_limits(ur_type):
    """The arm of each type, its estimated joint friction and rotor inertia included, holds its start pose under
    gravity and reaches a pose 0.4 to 1.5 rad away on each joint without touching itself, its joints never faster
    than the type's limits (the 120 deg/s joints reach theirs)."""
    sim = Simulator(sim_config_from_params({'ur_type': ur_type}))
    p, start = sim.params, sim.state().q.copy()
    rate = int(sim.control_rate)
    zero = np.zeros(6)

    def run(target, seconds):
        peak = zero
        for _ in range(int(seconds * rate)):
            sim.advance(sim.state(), TrajectorySample(target, zero, zero, 0, True))
            peak = np.maximum(peak, np.abs(sim.state().qd))
        return peak

    run(start, 1.0)
    np.testing.assert_allclose(sim.state().q, start, atol=1e-4)
    target = start + np.array([1.5, 0.4, 0.8, -1.5, 1.5, 1.5])
    peak = run(target, 6.0)
    np.testing.assert_allclose(sim.state().q, target, atol=5e-4)
    np.testing.assert_array_less(peak, p.v_max * 1.01)


@pytest.mark.timeout(120)
def test_a_ur_series_robot_comes_up_as_the_driver_expects_it():
    """A UR30: its component is named ur30 and active, it simulates at 500 Hz, and it moves."""
    with running_sim(ur_type='ur30') as h:
        cm = ControllerManagerClient(h)
        (component,) = cm.components()
        assert (component.name, component.state.id) == ('ur30', ACTIVE)
        assert h.sim.sim.control_rate == 500.0 and h.sim.sim.params.model == 'UR30'
        goal = h.send(h.goal([point(h.q + np.array([0.1, -0.1, 0.1, 0, 0, 0]), 1.0, ZERO)]))
        assert goal.accepted and h.result(goal)[1] == 0


@pytest.mark.timeout(120)
def test_a_driver_configured_for_another_robot_stays_unconfigured():
    """As upstream's robot-model test runs it: the driver for a UR20, the robot a UR5e, the component left
    unconfigured at start; configuring it is refused with the driver's message, and it stays unconfigured."""
    with running_sim(ur_type='ur20', simulated_ur_type='ur5e',
                     hardware_components_initial_state={'unconfigured': ['ur20']}) as h:
        cm = ControllerManagerClient(h)
        (component,) = cm.components()
        assert (component.name, component.state.id) == ('ur20', UNCONFIGURED)
        assert h.sim.sim.params.name == 'ur5e'  # the physics are the robot's
        response = cm.set_component_state('ur20', INACTIVE, 'inactive')
        assert not response.ok and response.state.id == UNCONFIGURED
        (component,) = cm.components()
        assert component.state.id == UNCONFIGURED
        assert 'active' not in cm.states().values()
