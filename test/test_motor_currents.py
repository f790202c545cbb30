"""Motor currents and "current as torque" (robot/motor_currents.py): the drive torques over each joint's torque
constant, within each type's drive range at rest and outstretched, raised by a payload as its gravity says, about 0 as
torques less gravity at rest; and the hardware's refusal of torques as efforts on a software that lacks them."""
import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from ur_sim_driver.controllers import startup
from ur_sim_driver.description.params import UR_TYPES
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.robot.motor_currents import (
    COULOMB_VELOCITY,
    current_as_torque,
    currents,
    drive_torques,
    motor_currents,
)
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

ZERO = np.zeros(6)
# The shoulder and elbow out straight, level: the largest gravity torques the arm meets on its own.
OUTSTRETCHED = (0.0, 0.0, 0.0, -np.pi / 2, 0.0, 0.0)
PAYLOAD = dict(mass=2.0, cog=np.array([0.0, 0.0, 0.05]), inertia=np.array([0.01, 0.01, 0.01, 0.0, 0.0, 0.0]))


def holding(sim: Simulator, q, seconds: float = 1.0) -> Simulator:
    """`sim` after holding `q` at rest for `seconds` of robot time."""
    q = np.asarray(q, dtype=float)
    for _ in range(int(seconds * sim.control_rate)):
        sim.advance(sim.state(), TrajectorySample(q, ZERO, ZERO, 0, True))
    assert np.abs(sim.state().qd).max() < 1e-5, 'not at rest'
    return sim


def test_the_coulomb_friction_the_servo_cancels_is_added_back_against_the_motion():
    effort, coulomb, limit = np.array([10.0, -5.0, 0.0]), np.array([3.0, 3.0, 0.5]), np.full(3, 150.0)
    qd = np.array([1.0, -1.0, 0.0])
    np.testing.assert_allclose(drive_torques(effort, qd, coulomb, True, limit), [13.0, -8.0, 0.0], atol=1e-9)
    np.testing.assert_array_equal(drive_torques(effort, qd, coulomb, False, limit), effort)  # felt in the physics
    slow = drive_torques(ZERO[:3], np.full(3, 0.1 * COULOMB_VELOCITY), coulomb, True, limit)
    assert (np.abs(slow) < 0.11 * coulomb).all()  # no jump at rest
    np.testing.assert_allclose(drive_torques(np.array([149.0, -149.0, 0.0]), qd, coulomb, True, limit),
                               [150.0, -150.0, 0.0], atol=1e-9)  # never beyond the drive's limit
    np.testing.assert_allclose(currents(np.array([13.5, -9.0]), np.array([13.5, 9.0])), [1.0, -1.0])


@pytest.mark.timeout(120)
@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_each_types_currents_are_its_gravity_torques_within_its_drive_range(ur_type):
    """At the start pose and outstretched, every joint's current is its torque over its constant, within the drive's
    range (the torque limit over the constant); outstretched, the shoulder carries the most of the arm."""
    shoulder = []
    for pose in (sim_config_from_params({}).initial_positions, OUTSTRETCHED):
        sim = holding(Simulator(sim_config_from_params({'ur_type': ur_type, 'initial_positions': list(pose)})), pose)
        p = sim.params
        limit = p.effort_max / p.torque_constant  # [A]
        i = motor_currents(sim)
        np.testing.assert_allclose(i * p.torque_constant, sim.state().effort, rtol=1e-12, atol=1e-12)  # at rest
        assert (np.abs(i) <= limit).all(), f'{ur_type} at {pose}: {i} A beyond {limit} A'
        shoulder.append(abs(i[1]))
    print(f'{ur_type}: shoulder {shoulder[0]:.2f} A at start, {shoulder[1]:.2f} A outstretched '
          f'(range {limit[1]:.1f} A)')
    assert shoulder[1] > shoulder[0] and shoulder[1] > 0.1 * limit[1]


def _gravity_shoulder(sim: Simulator, q, payload=None) -> float:
    """The shoulder's gravity torque [N m] by Pinocchio on the robot's own URDF, `payload` rigidly on tool0."""
    model = pin.buildModelFromXML(sim.urdf)
    if payload is not None:
        frame = model.frames[model.getFrameId('tool0')]
        inertia = pin.Inertia(payload['mass'], payload['cog'], np.diag(payload['inertia'][:3]))
        model.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    return float(pin.computeGeneralizedGravity(model, model.createData(), np.asarray(q, dtype=float))[1])


def test_a_payload_raises_the_shoulder_current_by_its_gravity_torque():
    def loaded(**payload):
        params = {'ur_type': 'ur5e', 'initial_positions': list(OUTSTRETCHED)}
        if payload:
            params.update({'mounted_payload.mass': payload['mass'], 'mounted_payload.cog': list(payload['cog']),
                           'mounted_payload.inertia': list(payload['inertia'])})
        return holding(Simulator(sim_config_from_params(params)), OUTSTRETCHED)

    without, with_payload = loaded(), loaded(**PAYLOAD)
    rise = motor_currents(with_payload)[1] - motor_currents(without)[1]  # [A]
    expected = (_gravity_shoulder(without, OUTSTRETCHED, PAYLOAD) - _gravity_shoulder(without, OUTSTRETCHED)) \
        / without.params.torque_constant[1]
    assert abs(expected) > 0.5  # 2 kg at the end of an outstretched UR5e: a clear rise
    assert rise == pytest.approx(expected, rel=0.01)


def test_current_as_torque_is_zero_at_rest_and_shows_a_payload_the_robot_was_not_told_of():
    sim = holding(Simulator(sim_config_from_params({'ur_type': 'ur5e', 'initial_positions': list(OUTSTRETCHED)})),
                  OUTSTRETCHED)
    assert np.abs(current_as_torque(sim)).max() < 1e-3 * sim.params.effort_max.max()
    params = {'ur_type': 'ur5e', 'initial_positions': list(OUTSTRETCHED), 'mounted_payload.mass': PAYLOAD['mass'],
              'mounted_payload.cog': list(PAYLOAD['cog']), 'mounted_payload.inertia': list(PAYLOAD['inertia'])}
    loaded = holding(Simulator(sim_config_from_params(params)), OUTSTRETCHED)
    unseen = current_as_torque(loaded)  # the robot believes no payload is mounted
    expected = _gravity_shoulder(loaded, OUTSTRETCHED, PAYLOAD) - _gravity_shoulder(loaded, OUTSTRETCHED)
    assert unseen[1] == pytest.approx(expected, rel=0.01)
    loaded.set_payload(**PAYLOAD)  # told of it: compensated
    assert np.abs(current_as_torque(loaded)).max() < 1e-3 * loaded.params.effort_max.max()


@pytest.mark.parametrize('params, refused', [
    ({'ur_type': 'ur5e'}, False),  # 5.25.1
    ({'ur_type': 'ur5e', 'software_version': '5.23.0'}, False),
    ({'ur_type': 'ur5e', 'software_version': '5.22.2'}, True),
    ({'ur_type': 'ur5'}, True),  # a CB3 never
    ({'ur_type': 'ur5e', 'software_version': '10.11.0'}, False),
    ({'ur_type': 'ur5e', 'software_version': '10.10.0'}, True),
])
def test_torques_as_efforts_are_refused_where_the_software_has_none(params, refused):
    cfg = sim_config_from_params({**params, 'use_currents_as_efforts': False})
    assert sim_config_from_params(params).use_currents_as_efforts  # currents by default, as at a16a268
    assert startup.configure_refusal(dataclasses.replace(cfg, use_currents_as_efforts=True)) is None
    if not refused:
        assert startup.configure_refusal(cfg) is None
        startup.check_start(cfg)
        return
    reason = startup.configure_refusal(cfg)
    assert reason == ('Driver configured to use actual torques as efforts, which is not supported by this software '
                      f'version {cfg.software_version}. Please use version 5.23.0 / 10.11.0 or newer for this feature.')
    with pytest.raises(ConfigError) as info:
        startup.check_start(cfg)
    assert reason in str(info.value) and "'use_currents_as_efforts' = false" in str(info.value)
    startup.check_start(dataclasses.replace(cfg, hardware_components_initial_state='unconfigured'))
