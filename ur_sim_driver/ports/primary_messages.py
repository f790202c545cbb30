"""The packages of the primary and secondary interfaces (TCP 30001 / 30002) as bytes, in the layouts the Universal
Robots Client Library parses (``primary_parser.h``, ``src/primary/robot_state/*.cpp`` and
``src/primary/robot_message/*.cpp``), and JointData, CartesianInfo and ToolData, which it skips but other clients
read, in the layout of a URSim capture in that library's tests (the same on 3.10-3.15 and 5.x). Big-endian
throughout. What is not simulated (voltages, temperatures) is NaN, as on RTDE.

A package is an int32 size (of the whole package, header included) and a uint8 type:

* ROBOT_STATE (16): sub-packages, each a uint32 size (header included), a uint8 type and its fields;
* ROBOT_MESSAGE (20): a uint64 timestamp, an int8 source, a uint8 message type and the message's fields.

Timestamps are simulated time in microseconds. Where the layout depends on the software version it follows the
version the robot runs: RobotModeData ends with a reserved byte from 3.5 on; ConfigurationData carries two reserved
int16 from 5.25.1 on (the client library reads them when present). No rclpy here.
"""
from __future__ import annotations

import math
import struct

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.description.params import URParams
from ur_sim_driver.ports.rtde_fields import READERS, joint_mode
from ur_sim_driver.robot.io_bank import VOLTAGE
from ur_sim_driver.robot.robot_state import (
    PAUSED,
    PLAYING,
    POWER_ON,
    PROTECTIVE_STOP,
    REDUCED,
    ROBOT_EMERGENCY_STOP,
    SYSTEM_EMERGENCY_STOP,
)
from ur_sim_driver.robot.software import SoftwareVersion

ROBOT_STATE, ROBOT_MESSAGE = 16, 20  # package types
ROBOT_MODE_DATA, JOINT_DATA, TOOL_DATA, MASTERBOARD_DATA, CARTESIAN_INFO, KINEMATICS_INFO, CONFIGURATION_DATA = \
    0, 1, 2, 3, 4, 5, 6  # robot state sub-packages
TEXT, VERSION, KEY, RUNTIME_EXCEPTION = 0, 3, 7, 10  # robot message types
SOURCE_CONTROLLER, SOURCE_RUNTIME = -2, -3  # message sources, as the client library's test data has them
PROGRAM_STARTED, PROGRAM_STOPPED = 'PROGRAM_XXX_STARTED', 'PROGRAM_XXX_STOPPED'  # key message titles
PROJECT_NAME = 'URControl'
BUILD_DATE = 'simulated'  # the version message's build date (build 0 marks the version as a simulated one)
CONTROL_MODE_POSITION = 0
# The robot type the controller reports (the client library's RobotType), by the model of config/ur_types.
ROBOT_TYPES = {'UR5': 1, 'UR10': 2, 'UR3': 3, 'UR16': 4, 'UR18': 5, 'UR8_LONG': 6, 'UR20': 7, 'UR30': 8, 'UR15': 9}
# URScript's movej and movel defaults: joint speed [rad/s] and acceleration [rad/s^2], tool speed [m/s] and
# acceleration [m/s^2].
V_JOINT, A_JOINT, V_TOOL, A_TOOL = 1.05, 1.4, 0.25, 1.2
MAX_TEXT = 64 * 1024  # [bytes] a message's text is cut to this


def microseconds(t: float) -> int:
    """Simulated time `t` [s] as a package timestamp [us]."""
    return max(0, round(t * 1e6))


def package(kind: int, body: bytes) -> bytes:
    return struct.pack('>iB', 5 + len(body), kind) + body


def sub_package(kind: int, body: bytes) -> bytes:
    return struct.pack('>IB', 5 + len(body), kind) + body


def _text(text: str) -> bytes:
    return text.encode('utf-8', errors='replace')[:MAX_TEXT]


# ---- robot messages -----------------------------------------------------------------------------------------------
def robot_message(kind: int, t: float, payload: bytes, source: int = SOURCE_CONTROLLER) -> bytes:
    """A robot message of type `kind` at simulated time `t` [s]."""
    return package(ROBOT_MESSAGE, struct.pack('>QbB', microseconds(t), source, kind) + payload)


def version_message(version: SoftwareVersion, t: float) -> bytes:
    """The controller's software version: project name, major and minor (uint8), bugfix and build (int32)."""
    name = PROJECT_NAME.encode()
    return robot_message(VERSION, t, struct.pack('>b', len(name)) + name
                         + struct.pack('>BBii', version.major, version.minor, version.bugfix, version.build)
                         + BUILD_DATE.encode())


def key_message(title: str, text: str, t: float, code: int = 0, argument: int = 0) -> bytes:
    """A key message (PROGRAM_XXX_STARTED / _STOPPED with the program's name as `text`)."""
    raw_title = title.encode()[:255]
    return robot_message(KEY, t, struct.pack('>iiB', code, argument, len(raw_title)) + raw_title + _text(text))


def runtime_exception(line: int, column: int, text: str, t: float) -> bytes:
    """A runtime (or compile) error of a program at `line`, `column` (1-based; 0: none)."""
    return robot_message(RUNTIME_EXCEPTION, t, struct.pack('>II', max(0, line), max(0, column)) + _text(text),
                         SOURCE_RUNTIME)


def text_message(text: str, t: float) -> bytes:
    """A program's textmsg."""
    return robot_message(TEXT, t, _text(text))


# ---- robot state --------------------------------------------------------------------------------------------------
def _bits(levels) -> int:
    return sum(1 << k for k, on in enumerate(levels) if on)


def robot_mode_data(host: Host, version: SoftwareVersion) -> bytes:
    """Under the simulation lock: modes, program state and speed scaling now. The real robot is reported connected
    and enabled (the simulated arm stands in for it); the control mode is always position."""
    robot, scaling = host.robot, host.speed_scaling
    body = struct.pack('>Q7?bBddd', microseconds(host.sim.time), True, True, robot.robot_mode >= POWER_ON,
                       robot.safety_mode in (SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP),
                       robot.safety_mode == PROTECTIVE_STOP, robot.program_state == PLAYING,
                       robot.program_state == PAUSED, robot.robot_mode, CONTROL_MODE_POSITION,
                       float(scaling.slider), float(scaling.factor), 1.0)
    if version[:2] >= (3, 5):
        body += b'\x00'  # reserved
    return sub_package(ROBOT_MODE_DATA, body)


NAN = float('nan')


def joint_data(host: Host) -> bytes:
    """Under the simulation lock: per joint (interleaved) actual and target position, actual velocity and motor
    current (as RTDE's), voltage, motor and micro temperature (float; not simulated: NaN, the deprecated micro one 0)
    and the joint mode."""
    q, q_target, qd, current = (READERS[n](host) for n in ('actual_q', 'target_q', 'actual_qd', 'actual_current'))
    mode = joint_mode(host.robot.robot_mode)
    body = b''.join(struct.pack('>3d4fB', q[j], q_target[j], qd[j], current[j], NAN, NAN, 0.0, mode)
                    for j in range(6))
    return sub_package(JOINT_DATA, body)


def cartesian_info(host: Host) -> bytes:
    """Under the simulation lock: the TCP pose (x, y, z [m], rotation vector [rad]; base frame, the flange: the
    installation sets no TCP offset) and the TCP offset (zeros)."""
    return sub_package(CARTESIAN_INFO, struct.pack('>12d', *READERS['actual_TCP_pose'](host),
                                                   *READERS['tcp_offset'](host)))


def tool_data(host: Host) -> bytes:
    """Under the simulation lock: the tool's analog input ranges (1 voltage, 0 current) and values, its 48 V supply
    (NaN), output voltage [V] (0, 12 or 24), current and temperature (NaN) and its mode (as the joints')."""
    io = host.sim.io
    ranges = (int(r == VOLTAGE) for r in io.tool_analog_in_range)
    body = struct.pack('>BBddfBffB', *ranges, *io.tool_analog_in, NAN, int(io.tool_voltage), NAN, NAN,
                       joint_mode(host.robot.robot_mode))
    return sub_package(TOOL_DATA, body)


def masterboard_data(host: Host) -> bytes:
    """Under the simulation lock: the control box's IO and safety mode. Temperature, voltage and currents are not
    simulated (0); no Euromap67 interface is installed."""
    io, safety = host.sim.io, host.robot.safety_mode
    body = struct.pack('>IIBBddbbdd4fB??IB?B', _bits(io.digital_in), _bits(io.digital_out),
                       *io.analog_in_domain, *io.analog_in, *io.analog_out_domain, *io.analog_out,
                       0.0, 0.0, 0.0, 0.0, safety, safety == REDUCED, False, 0, 0, False, 0)
    return sub_package(MASTERBOARD_DATA, body)


def _dh(params: URParams) -> tuple[tuple[float, ...], ...]:
    """(theta, a, d, alpha) of the six joints: the nominal model, no calibration deltas."""
    dh = params.dh
    half = math.pi / 2
    return ((0.0,) * 6, (0.0, dh.a2, dh.a3, 0.0, 0.0, 0.0), (dh.d1, 0.0, 0.0, dh.d4, dh.d5, dh.d6),
            (half, 0.0, 0.0, half, -half, 0.0))


def kinematics_info(params: URParams) -> bytes:
    """The calibration: per joint a checksum (0: not simulated), then DH theta, a, d, alpha and a status (0)."""
    theta, a, d, alpha = _dh(params)
    return sub_package(KINEMATICS_INFO, struct.pack('>6I24dI', *(0,) * 6, *theta, *a, *d, *alpha, 0))


def configuration_data(params: URParams, version: SoftwareVersion) -> bytes:
    """Joint limits, URScript's default speeds, DH parameters and the robot type (masterboard version, controller
    box type and robot sub type are not simulated: 0; nor is the equivalent radius)."""
    theta, a, d, alpha = _dh(params)
    limits = [x for lo, hi in zip(params.q_min, params.q_max) for x in (float(lo), float(hi))]
    motion = [x for v in params.v_max for x in (float(v), float(params.a_max))]
    body = struct.pack('>24d5d24d4i', *limits, *motion, V_JOINT, A_JOINT, V_TOOL, A_TOOL, 0.0,
                       *a, *d, *alpha, *theta, 0, 0, ROBOT_TYPES.get(params.model, 0), 0)
    if version[:3] >= (5, 25, 1):
        body += struct.pack('>hh', 0, 0)  # reserved
    return sub_package(CONFIGURATION_DATA, body)


def robot_state(*subs: bytes) -> bytes:
    return package(ROBOT_STATE, b''.join(subs))


def robot_state_now(host: Host, version: SoftwareVersion, kinematics: bytes, configuration: bytes) -> bytes:
    """Under the simulation lock: the robot state package, its sub-packages in the order the robot sends them
    (robot mode, joints, Cartesian, kinematics, masterboard, tool, configuration)."""
    return robot_state(robot_mode_data(host, version), joint_data(host), cartesian_info(host), kinematics,
                       masterboard_data(host), tool_data(host), configuration)
