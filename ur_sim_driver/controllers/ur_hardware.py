"""The UR hardware interface as ros2_control's controller manager sees it, without ROS.

The UR driver's hardware component exports, per joint, the command interfaces ``<joint>/position``,
``<joint>/velocity`` and ``<joint>/effort`` and the state interfaces ``position``, ``velocity``, ``effort``; besides
them GPIO-like interfaces named after a function (``<tf_prefix>trajectory_passthrough/...``,
``<tf_prefix>freedrive_mode/...``, ``<tf_prefix>tool_contact/...``,
``<tf_prefix>speed_scaling/speed_scaling_factor``, ...). Each command interface a controller claims starts a *mode*
of the robot, and the hardware refuses a switch that would run two modes that cannot run together
(``prepare_command_mode_switch``): position, velocity and passthrough exclude one another and freedrive; effort
(torque control, robot software 5.23.0 / 10.10.0 or later) excludes all of them; tool contact runs beside position,
velocity, effort and passthrough; force mode beside passthrough. Facts from ``ur_robot_driver``
(hardware_interface.cpp and its mode compatibility table); the code is ours."""
from __future__ import annotations

from collections.abc import Iterable

from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.robot.software import CURRENT_AS_TORQUE, TORQUE_CONTROL, SoftwareVersion, supports

POSITION, VELOCITY, EFFORT = 'position', 'velocity', 'effort'
FORCE_MODE, PASSTHROUGH, FREEDRIVE, TOOL_CONTACT = 'force_mode', 'trajectory_passthrough', 'freedrive_mode', \
    'tool_contact'
JOINT_MODES = (POSITION, VELOCITY, EFFORT)
GPIO_MODES = (FORCE_MODE, PASSTHROUGH, FREEDRIVE, TOOL_CONTACT)

# Pairs of different modes that may run at the same time; every other pair of different modes may not.
_COMPATIBLE = frozenset(frozenset(p) for p in (
    (POSITION, TOOL_CONTACT), (VELOCITY, TOOL_CONTACT), (EFFORT, TOOL_CONTACT),
    (FORCE_MODE, PASSTHROUGH), (PASSTHROUGH, TOOL_CONTACT)))


def compatible(a: str, b: str) -> bool:
    """True when modes `a` and `b` may run together (a mode is compatible with itself)."""
    return a == b or frozenset((a, b)) in _COMPATIBLE


def mode_of(interface: str, tf_prefix: str) -> str | None:
    """The robot mode a command interface belongs to ('position', 'trajectory_passthrough', ...), or None for
    interfaces that start no mode (IO, payload, ...)."""
    head, _, tail = interface.rpartition('/')
    if head and tail in JOINT_MODES:
        return tail
    for mode in GPIO_MODES:
        if head == f'{tf_prefix}{mode}':
            return mode
    return None


EFFORT_TOO_OLD = ('Requested to use effort interface on a robot version that doesn\'t support it. Torque control is '
                  'available from robot software 5.23.0 / 10.10.0 on.')


def prepare_command_mode_switch(start: Iterable[str], stop: Iterable[str], running: Iterable[str],
                                tf_prefix: str, version: SoftwareVersion | None = None) -> str | None:
    """What the hardware says to a switch: None when it can be done, else why not.

    Args:
        start: command interfaces the activating controllers claim.
        stop: command interfaces the deactivating controllers release.
        running: command interfaces claimed now (before the switch).
        tf_prefix: the robot's tf_prefix (part of the GPIO interface names).
        version: the robot's software (effort needs 5.23.0 / 10.10.0); None: not checked.
    """
    stopping = {m for m in (mode_of(i, tf_prefix) for i in stop) if m is not None}
    remaining = {m for m in (mode_of(i, tf_prefix) for i in running) if m is not None} - stopping
    started: list[str] = []
    for mode in (mode_of(i, tf_prefix) for i in start):
        if mode is None or mode in started:
            continue
        for other in started:
            if not compatible(mode, other):
                return f'Starting {mode} together with {other} is not allowed.'
        started.append(mode)
    if EFFORT in started and version is not None and not supports(version, TORQUE_CONTROL):
        return EFFORT_TOO_OLD
    for mode in started:
        for other in sorted(remaining):
            if not compatible(mode, other):
                return f'Starting {mode} together with {other} is not allowed.'
    return None


def command_interfaces(joints: Iterable[str], tf_prefix: str) -> tuple[str, ...]:
    """Every command interface the emulated hardware exports that moves the arm (joint and mode GPIOs)."""
    names = [f'{j}/{kind}' for j in joints for kind in (POSITION, VELOCITY, EFFORT)]
    p = tf_prefix
    for i in range(6):
        names += [f'{p}{PASSTHROUGH}/setpoint_positions_{i}', f'{p}{PASSTHROUGH}/setpoint_velocities_{i}',
                  f'{p}{PASSTHROUGH}/setpoint_accelerations_{i}']
    names += [f'{p}{PASSTHROUGH}/{n}' for n in ('abort', 'transfer_state', 'time_from_start', 'trajectory_size')]
    names += [f'{p}{FREEDRIVE}/{n}' for n in ('async_success', 'enable', 'abort')]
    names += [f'{p}{TOOL_CONTACT}/tool_contact_set_state']
    return tuple(names) + friction_interfaces(tf_prefix) + gravity_interfaces(tf_prefix)


def gravity_interfaces(tf_prefix: str) -> tuple[str, ...]:
    """The gravity update's command interfaces: the vector and the async success flag (they start no mode)."""
    return tuple(f'{tf_prefix}gravity/{n}' for n in ('x', 'y', 'z', 'gravity_async_success'))


def friction_interfaces(tf_prefix: str) -> tuple[str, ...]:
    """The friction model's command interfaces: 6 viscous and 6 Coulomb scales and the async success flag (they
    start no mode)."""
    p = f'{tf_prefix}friction_model/'
    return (*(f'{p}viscous_{i}' for i in range(6)), *(f'{p}coulomb_{i}' for i in range(6)), f'{p}async_success')


def state_interfaces(joints: Iterable[str], tf_prefix: str) -> tuple[str, ...]:
    """The state interfaces the emulated hardware exports that ur_sim's controllers read."""
    p = tf_prefix
    names = [f'{j}/{kind}' for j in joints for kind in (POSITION, VELOCITY, EFFORT)]
    names.append(f'{p}speed_scaling/speed_scaling_factor')
    names += [f'{p}tcp_pose/{axis}' for axis in ('position.x', 'position.y', 'position.z', 'orientation.x',
                                                 'orientation.y', 'orientation.z', 'orientation.w')]
    names += [f'{p}tcp_fts_sensor/{axis}' for axis in ('force.x', 'force.y', 'force.z', 'torque.x', 'torque.y',
                                                       'torque.z')]
    names += [f'{p}{TOOL_CONTACT}/{n}' for n in ('tool_contact_result', 'tool_contact_state')]
    return tuple(names)


def prefixed_joints(joints: Iterable[str], tf_prefix: str) -> tuple[str, ...]:
    """The controllers' joint names: the configured ones with the tf_prefix where it is missing (as the
    simulator names them)."""
    return tuple(j if j.startswith(tf_prefix) else tf_prefix + j for j in joints)


def joint_interfaces(joints: Iterable[str], *kinds: str) -> tuple[str, ...]:
    """``<joint>/<kind>`` for every joint and kind, joint-major, as ros2_control's controllers list them."""
    return tuple(f'{j}/{k}' for j in joints for k in kinds)


def robot_model_refusal(ur_type: str, robot_type: str, version: SoftwareVersion) -> str | None:
    """The hardware's refusal to configure for `ur_type` when the robot is a `robot_type`, or None.

    As ``on_configure`` with ``verify_robot_model``: the robot reports its model and series (a ur7e reports as a
    UR5 of the e-Series, so a driver configured for a ur5e accepts it), and the two must agree.
    """
    expected, robot = load_ur_params(ur_type), load_ur_params(robot_type)
    if (expected.model, expected.series) == (robot.model, robot.series):
        return None
    return (f"The connected robot is of type '{robot.model}' and version {version} but the driver was configured for "
            f"type '{ur_type}'. Please check the 'ur_type' parameter and make sure it matches your actual robot. "
            'This can lead to critical inaccuracies of tcp positions.')


def torque_efforts_refusal(version: SoftwareVersion) -> str | None:
    """The hardware's refusal to configure with ``use_currents_as_efforts: false`` on a robot whose software has
    no ``actual_current_as_torque`` (before 5.23.0 / 10.11.0, and every CB3), in the driver's words; None where it
    has it."""
    if supports(version, CURRENT_AS_TORQUE):
        return None
    return ('Driver configured to use actual torques as efforts, which is not supported by this software version '
            f'{version}. Please use version 5.23.0 / 10.11.0 or newer for this feature.')
