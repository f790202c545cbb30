"""What each RTDE variable reads from and writes to the simulated robot.

Output variables are read under the simulation lock, from the same objects the ROS side reads: the arm (joint
state, servo setpoint, TCP pose, wrench, payload), the robot's modes and program state, the IO bank, the speed
scaling and the registers, the joints' motor currents (``robot/motor_currents.py``). The other electrical and thermal
values a UR reports (voltages, temperatures, the robot's current, the controller's execution time) and the tool
accelerometer and momentum are not simulated: they are NaN, a value no
client can take for a measurement, so that clients that ask for them (ur_rtde's RTDEReceiveInterface asks for
every variable by default) still run. Any other variable ur_sim does not fill (Euromap67, ...) is answered
``NOT_FOUND`` at set-up, as the robot answers a name it does not know. Input variables change the robot as the
driver's services do: an output set here shows on ``/io_and_status_controller/io_states``, and the other way round.

Frames and units as the RTDE guide gives them: poses ``[x, y, z, rx, ry, rz]`` in the base frame (rotation
vector), ``actual_TCP_force`` in the base frame about the TCP, joint values in rad, rad/s, rad/s^2 and N m. The TCP
is the flange (tool0) until a program's set_tcp moves it (the installation sets no TCP offset).
"""
from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.controllers.io_and_status import TOOL_TEMPERATURE
from ur_sim_driver.robot.encoders import reported_velocity
from ur_sim_driver.robot.io_bank import CURRENT, N_ANALOG, VOLTAGE, analog_out_refusal
from ur_sim_driver.robot.motor_currents import current_as_torque, motor_currents
from ur_sim_driver.robot.registers import bits_word, set_bits_word
from ur_sim_driver.robot.robot_state import (
    PAUSED,
    PLAYING,
    POWER_ON,
    PROTECTIVE_STOP,
    ROBOT_EMERGENCY_STOP,
    SYSTEM_EMERGENCY_STOP,
)
from ur_sim_driver.robot.software import CURRENT_AS_TORQUE, SoftwareVersion, supports
from ur_sim_driver.robot.speed_scaling import SLIDER_MAX

NAN = float('nan')  # a value ur_sim does not simulate
NAN6 = (NAN,) * 6
RUNTIME_STATE = {'STOPPED': 1, PLAYING: 2, PAUSED: 4}  # stopping 0, pausing 3, resuming 5: transitions are instant
_STOPPED_BY_SAFETY = (PROTECTIVE_STOP, 5, SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP, 8, 9)  # bit 10


def _vec(a) -> tuple[float, ...]:
    return tuple(float(x) for x in a)


def _bits(levels) -> int:
    return sum(1 << k for k, on in enumerate(levels) if on)


def _rotvec(quat_wxyz: np.ndarray) -> np.ndarray:
    """(3,) the rotation vector [rad] of a unit quaternion (w, x, y, z), its angle in [0, pi]. MuJoCo's C routine:
    every cycle for each TCP pose streamed (SciPy's Rotation takes 50 us of a 2 ms cycle, this 3 us; bench_tricks)."""
    rv = np.empty(3)
    mujoco.mju_quat2Vel(rv, quat_wxyz, 1.0)
    return rv


def _pose(host: Host) -> tuple[float, ...]:
    position, (x, y, z, w) = host.sim.tcp_pose()
    return _vec(np.concatenate((position, _rotvec(np.array((w, x, y, z))))))


def _target(host: Host, k: int) -> tuple[float, ...]:
    setpoint = host.sim.last_setpoint
    if setpoint is None:  # freedrive, or before the first cycle: the arm's own state
        state = host.sim.state()
        return _vec((state.q, state.qd, np.zeros_like(state.q))[k])
    return _vec((setpoint.positions, setpoint.velocities, setpoint.accelerations)[k])


def _target_tcp(host: Host) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """(target_TCP_pose, target_TCP_speed): the TCP where the servo's setpoint puts it, and its twist."""
    position, rotation, twist = host.sim.tcp_at(np.array(_target(host, 0)), np.array(_target(host, 1)))
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).ravel())
    return _vec(np.concatenate((position, _rotvec(quat)))), _vec(twist)


def _elbow(host: Host) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The elbow (the forearm link's origin, on the elbow joint's axis): position [m] and velocity [m/s], base frame."""
    body = host.sim.physics.body_id(host.cfg.tf_prefix + 'forearm_link')
    if body is None:
        return (NAN,) * 3, (NAN,) * 3
    position, velocity = host.sim.physics.body_motion(body)
    return _vec(position), _vec(velocity)


def joint_mode(robot_mode: int) -> int:
    """The joints' mode for a robot mode: 253 RUNNING, 255 IDLE (powered, brakes on), 238 BACKDRIVE, 247 BOOTING,
    239 POWER_OFF."""
    return {7: 253, 4: 255, 5: 255, 6: 238, 2: 247}.get(robot_mode, 239)


def _safety_bits(mode: int) -> int:
    bits = 1 << (mode - 1) if 1 <= mode <= 9 else 0
    if mode in (SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP):
        bits |= 1 << 7  # emergency stopped
    if mode in _STOPPED_BY_SAFETY:
        bits |= 1 << 10
    return bits


def _register_readers() -> dict[str, Callable[[Host], object]]:
    out: dict[str, Callable[[Host], object]] = {}
    for side in ('input', 'output'):
        for k in range(48):
            out[f'{side}_int_register_{k}'] = lambda h, s=side, k=k: getattr(h.robot.registers, f'{s}_ints')[k]
            out[f'{side}_double_register_{k}'] = lambda h, s=side, k=k: getattr(h.robot.registers, f'{s}_doubles')[k]
        for k in range(64, 128):
            out[f'{side}_bit_register_{k}'] = lambda h, s=side, k=k: getattr(h.robot.registers, f'{s}_bits')[k]
        for first in (0, 32):
            out[f'{side}_bit_registers{first}_to_{first + 31}'] = \
                lambda h, s=side, f=first: bits_word(getattr(h.robot.registers, f'{s}_bits'), f)
    return out


_UNREAD = object()

#: Output variable -> its value now (call under the simulation lock).
READERS: dict[str, Callable[[Host], object]] = {
    'timestamp': lambda h: h.sim.time,
    'target_q': lambda h: _target(h, 0), 'target_qd': lambda h: _target(h, 1), 'target_qdd': lambda h: _target(h, 2),
    'target_moment': lambda h: _vec(h.sim.state().effort),
    # The motor currents [A] from the drive torques (robot/motor_currents.py); the servo's target torque is the one
    # the drives deliver in the simulation, so the target current is the actual one.
    'actual_current': lambda h: _vec(motor_currents(h.sim)), 'target_current': lambda h: _vec(motor_currents(h.sim)),
    'actual_current_as_torque': lambda h: _vec(current_as_torque(h.sim)),  # less the believed gravity [N m]
    'actual_q': lambda h: _vec(h.sim.state().q),
    'actual_qd': lambda h: _vec(reported_velocity(h.sim.state().qd, h.sim.control_dt)),
    'actual_TCP_pose': _pose, 'actual_TCP_force': lambda h: _vec(h.sim.tcp_force()),
    'tcp_offset': lambda h: _vec(h.sim.tcp_offset),
    'actual_TCP_speed': lambda h: _vec(h.sim.tcp_velocity()),
    'target_TCP_pose': lambda h: _target_tcp(h)[0], 'target_TCP_speed': lambda h: _target_tcp(h)[1],
    'speed_scaling': lambda h: h.speed_scaling.factor, 'target_speed_fraction': lambda h: h.speed_scaling.slider,
    'robot_mode': lambda h: h.robot.robot_mode, 'safety_mode': lambda h: h.robot.safety_mode,
    'safety_status': lambda h: h.robot.safety_mode,
    'runtime_state': lambda h: RUNTIME_STATE.get(h.robot.program_state, 1),
    'robot_status_bits': lambda h: int(h.robot.robot_mode >= POWER_ON) | int(h.robot.program_running) << 1,
    'safety_status_bits': lambda h: _safety_bits(h.robot.safety_mode),
    'actual_digital_input_bits': lambda h: _bits(h.sim.io.digital_in),
    'actual_digital_output_bits': lambda h: _bits(h.sim.io.digital_out),
    'standard_analog_input0': lambda h: h.sim.io.analog_in[0],
    'standard_analog_input1': lambda h: h.sim.io.analog_in[1],
    'standard_analog_output0': lambda h: h.sim.io.analog_out[0],
    'standard_analog_output1': lambda h: h.sim.io.analog_out[1],
    'analog_io_types': lambda h: (_bits(d == VOLTAGE for d in h.sim.io.analog_in_domain)
                                  | _bits(d == VOLTAGE for d in h.sim.io.analog_out_domain) << 2),
    'tool_analog_input0': lambda h: h.sim.io.tool_analog_in[0],
    'tool_analog_input1': lambda h: h.sim.io.tool_analog_in[1],
    'tool_analog_input_types': lambda h: _bits(d == VOLTAGE for d in h.sim.io.tool_analog_in_range),
    'tool_output_voltage': lambda h: h.sim.io.tool_voltage,
    'payload': lambda h: h.sim.payload.mass, 'payload_cog': lambda h: _vec(h.sim.payload.cog),
    'payload_inertia': lambda h: _vec(h.sim.payload.inertia),
    'script_control_line': lambda h: 0,
    'elbow_position': lambda h: _elbow(h)[0], 'elbow_velocity': lambda h: _elbow(h)[1],
    'joint_mode': lambda h: (joint_mode(h.robot.robot_mode),) * 6,
    'ft_raw_wrench': lambda h: _vec(h.sim.raw_wrench()),  # neither zeroed nor payload-compensated; tool0 axes
    **{name: (lambda h: NAN6) for name in ('joint_control_output', 'joint_temperatures', 'actual_joint_voltage')},
    **{name: (lambda h: NAN) for name in ('actual_execution_time', 'actual_momentum', 'actual_main_voltage',
                                           'actual_robot_voltage', 'actual_robot_current')},
    'actual_tool_accelerometer': lambda h: (NAN,) * 3,
    # What the Client Library asks for (its exhaustive test recipe): served, as by the robot, whether or not
    # ur_sim simulates it. The tool's current and temperature are the ROS tool_data's (io_and_status.py); currents,
    # energies, deviation and collision ratios, accelerations are not simulated (NaN); no Euromap67 interface or
    # encoder is installed (0); the base does not move.
    'tool_mode': lambda h: joint_mode(h.robot.robot_mode),
    'tool_output_current': lambda h: 0.0, 'tool_temperature': lambda h: TOOL_TEMPERATURE,
    **{name: (lambda h: 0) for name in ('tool_output_mode', 'tool_digital_output0_mode', 'tool_digital_output1_mode',
                                        'encoder0_raw', 'encoder1_raw', 'euromap67_input_bits',
                                        'euromap67_output_bits', 'time_scale_source')},
    'actual_configurable_digital_input_bits': lambda h: _bits(h.sim.io.digital_in[8:16]),
    'actual_configurable_digital_output_bits': lambda h: _bits(h.sim.io.digital_out[8:16]),
    'target_execution_time': lambda h: h.sim.control_dt,
    'tcp_force_scalar': lambda h: float(np.linalg.norm(h.sim.tcp_force()[:3])),
    # as set_gravity takes it: the direction opposite to gravity, up for an upright robot [m/s^2]
    'target_gravity': lambda h: _vec(h.sim.gravity_belief if h.sim.gravity_belief is not None
                                     else -h.sim.physics.gravity_in_base()),
    'control_step': lambda h: round(h.sim.time / h.sim.control_dt),
    'target_base_acceleration': lambda h: (0.0,) * 6,
    **{name: (lambda h: NAN6) for name in ('actual_current_window', 'actual_TCP_acceleration',
                                            'target_TCP_acceleration', 'wrench_calc_from_currents',
                                            'target_base_wrench')},
    **{name: (lambda h: NAN) for name in ('io_current', 'actual_robot_energy_consumed',
                                           'actual_robot_braking_energy_dissipated', 'euromap67_24V_voltage',
                                           'euromap67_24V_current', 'joint_position_deviation_ratio',
                                           'collision_detection_ratio')},
    **_register_readers(),
}

#: Output variables newer than some robots: the first software versions (PolyScope 5, PolyScope X) that have them;
#: an older robot (every CB3) answers NOT_FOUND, as for a name it does not know. actual_current_as_torque: the
#: driver's use_currents_as_efforts check (software.CURRENT_AS_TORQUE).
NEWER_OUTPUTS: dict[str, tuple] = {'actual_current_as_torque': CURRENT_AS_TORQUE}


def served(name: str, version: SoftwareVersion) -> bool:
    """The robot of software `version` fills output variable `name`."""
    minima = NEWER_OUTPUTS.get(name)
    return name in READERS and (minima is None or supports(version, minima))


#: Input variables a client may write (the others of the protocol's input list answer NOT_FOUND).
WRITABLE = frozenset({
    'speed_slider_mask', 'speed_slider_fraction', 'standard_digital_output_mask', 'standard_digital_output',
    'configurable_digital_output_mask', 'configurable_digital_output', 'tool_digital_output_mask',
    'tool_digital_output', 'standard_analog_output_mask', 'standard_analog_output_type', 'standard_analog_output_0',
    'standard_analog_output_1', 'external_force_torque', 'input_bit_registers0_to_31', 'input_bit_registers32_to_63',
    *(f'input_bit_register_{k}' for k in range(64, 128)), *(f'input_int_register_{k}' for k in range(48)),
    *(f'input_double_register_{k}' for k in range(48)),
})


def write(host: Host, values: dict[str, object]) -> list[str]:
    """Apply one input data package (variable -> value) under the simulation lock; what was refused, as messages
    naming the variable, the value and the limit (the rest is applied)."""
    refused: list[str] = []
    io = host.sim.io
    for name, first, count in (('standard_digital_output', 0, 8), ('configurable_digital_output', 8, 8),
                               ('tool_digital_output', 16, 2)):
        if name in values:
            mask = int(values.get(f'{name}_mask', 0xFF))
            for k in range(count):
                if mask >> k & 1:
                    io = io.with_digital_out(first + k, float(int(values[name]) >> k & 1))
    if 'standard_analog_output_mask' in values:
        mask, kinds = int(values['standard_analog_output_mask']), int(values.get('standard_analog_output_type', 0))
        for k in range(N_ANALOG):
            name = f'standard_analog_output_{k}'
            if mask >> k & 1 and name in values:
                domain = VOLTAGE if kinds >> k & 1 else CURRENT
                refusal = analog_out_refusal(k, float(values[name]), domain)
                if refusal:
                    refused.append(f'{name} = {values[name]}: {refusal}')
                else:
                    io = io.with_analog_out(k, float(values[name]), domain)
    host.sim.io = io
    if int(values.get('speed_slider_mask', 0)) & 1 and 'speed_slider_fraction' in values:
        f = float(values['speed_slider_fraction'])
        if 0.0 <= f <= SLIDER_MAX:  # RTDE takes the whole slider, 0 included (the driver's service: from 0.01)
            host.speed_scaling.slider = f
        else:
            refused.append(f'speed_slider_fraction = {f} is outside [0, {SLIDER_MAX}]')
    if 'external_force_torque' in values:  # read while ft_rtde_input_enable has enabled the external sensor
        reading = np.array(values['external_force_torque'], dtype=float)
        if np.all(np.isfinite(reading)):
            host.sim.external_ft_input = reading
        else:
            refused.append(f'external_force_torque = {reading.tolist()}: not finite')
    written = host.robot.rtde_inputs  # for URScript's rtde_set_watchdog
    for name in values:
        written[name] = host.sim.time
    registers = host.robot.registers
    for name, value in values.items():
        if name.startswith('input_int_register_'):
            registers.input_ints[int(name.rsplit('_', 1)[1])] = int(value)
        elif name.startswith('input_double_register_'):
            registers.input_doubles[int(name.rsplit('_', 1)[1])] = float(value)
        elif name.startswith('input_bit_register_'):
            registers.input_bits[int(name.rsplit('_', 1)[1])] = bool(value)
        elif name.startswith('input_bit_registers'):
            set_bits_word(registers.input_bits, 0 if name.endswith('0_to_31') else 32, int(value))
    return refused


class CycleValues:
    """The output variables of the control cycle just run, each read at most once however many readers ask for it
    (RTDE's sessions, the real-time interface): one cycle's package of a dozen clients costs what one costs. The
    reads are made under the simulation lock, after the cycle; the simulated time moving on starts a new cycle."""

    def __init__(self, host: Host) -> None:
        self.host = host
        self._time = math.nan
        self._values: dict[str, object] = {}

    def __getitem__(self, name: str) -> object:
        time = self.host.sim.time
        if time != self._time:
            self._time, self._values = time, {}
        value = self._values.get(name, _UNREAD)
        if value is _UNREAD:
            value = self._values[name] = READERS[name](self.host)
        return value

