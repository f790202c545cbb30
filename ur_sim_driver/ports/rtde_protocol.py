"""The RTDE wire protocol (TCP 30004 on a UR), without sockets: package framing, the variable types and names, and
the encoding of values. Facts from UR's RTDE guide and the Universal Robots Client Library (``package_header.h``,
``data_package.cpp``): every package is a big-endian ``uint16`` size (header included), a ``uint8`` type and a
payload; a recipe's types are answered as comma-separated names; a data package is a ``uint8`` recipe id
(protocol 2) and the values in recipe order.
"""
from __future__ import annotations

import struct
from collections.abc import Sequence

from ur_sim_driver.errors import UrSimError

# Package types (ASCII letters)
REQUEST_PROTOCOL_VERSION = ord('V')
GET_URCONTROL_VERSION = ord('v')
TEXT_MESSAGE = ord('M')
DATA_PACKAGE = ord('U')
SETUP_OUTPUTS = ord('O')
SETUP_INPUTS = ord('I')
START = ord('S')
PAUSE = ord('P')
HEADER = struct.Struct('>HB')

NOT_FOUND, IN_USE = 'NOT_FOUND', 'IN_USE'
# Wire type name -> struct format of one value (big-endian)
FORMATS = {'BOOL': '?', 'UINT8': 'B', 'UINT32': 'I', 'UINT64': 'Q', 'INT32': 'i', 'DOUBLE': 'd',
           'VECTOR3D': '3d', 'VECTOR6D': '6d', 'VECTOR6INT32': '6i', 'VECTOR6UINT32': '6I'}


def _numbered(prefix: str, first: int, last: int, kind: str) -> dict[str, str]:
    return {f'{prefix}{k}': kind for k in range(first, last + 1)}


# Variables a client may write (input recipes) and read back (output recipes: the registers too).
INPUTS: dict[str, str] = {
    'speed_slider_mask': 'UINT32', 'speed_slider_fraction': 'DOUBLE',
    'standard_digital_output_mask': 'UINT8', 'standard_digital_output': 'UINT8',
    'configurable_digital_output_mask': 'UINT8', 'configurable_digital_output': 'UINT8',
    'tool_digital_output_mask': 'UINT8', 'tool_digital_output': 'UINT8',
    'standard_analog_output_mask': 'UINT8', 'standard_analog_output_type': 'UINT8',
    'standard_analog_output_0': 'DOUBLE', 'standard_analog_output_1': 'DOUBLE',
    'external_force_torque': 'VECTOR6D',
    'input_bit_registers0_to_31': 'UINT32', 'input_bit_registers32_to_63': 'UINT32',
    **_numbered('input_bit_register_', 64, 127, 'BOOL'), **_numbered('input_int_register_', 0, 47, 'INT32'),
    **_numbered('input_double_register_', 0, 47, 'DOUBLE'),
}
_VECTOR6D = ('target_q', 'target_qd', 'target_qdd', 'target_current', 'target_moment', 'actual_q', 'actual_qd',
             'actual_current', 'actual_current_window', 'actual_current_as_torque', 'joint_control_output',
             'actual_TCP_pose', 'actual_TCP_speed', 'actual_TCP_force', 'target_TCP_pose', 'target_TCP_speed',
             'tcp_offset', 'actual_TCP_acceleration', 'target_TCP_acceleration', 'joint_temperatures',
             'actual_joint_voltage', 'ft_raw_wrench', 'wrench_calc_from_currents', 'payload_inertia',
             'target_base_acceleration', 'target_base_wrench')
_DOUBLE = ('timestamp', 'actual_execution_time', 'target_execution_time', 'speed_scaling', 'target_speed_fraction',
           'actual_momentum', 'actual_main_voltage', 'actual_robot_voltage', 'actual_robot_current',
           'standard_analog_input0', 'standard_analog_input1', 'standard_analog_output0', 'standard_analog_output1',
           'io_current', 'actual_robot_energy_consumed', 'actual_robot_braking_energy_dissipated',
           'euromap67_24V_voltage', 'euromap67_24V_current', 'tool_analog_input0', 'tool_analog_input1',
           'tool_output_current', 'tool_temperature', 'tcp_force_scalar', 'joint_position_deviation_ratio',
           'collision_detection_ratio', 'payload')
OUTPUTS: dict[str, str] = {
    **{name: 'VECTOR6D' for name in _VECTOR6D}, **{name: 'DOUBLE' for name in _DOUBLE},
    **{name: 'VECTOR3D' for name in ('actual_tool_accelerometer', 'elbow_position', 'elbow_velocity',
                                      'payload_cog', 'target_gravity')},
    **{name: 'UINT64' for name in ('actual_digital_input_bits', 'actual_configurable_digital_input_bits',
                                    'actual_digital_output_bits', 'actual_configurable_digital_output_bits',
                                    'control_step')},
    **{name: 'UINT32' for name in ('runtime_state', 'robot_status_bits', 'safety_status_bits', 'analog_io_types',
                                    'euromap67_input_bits', 'euromap67_output_bits', 'tool_mode',
                                    'tool_analog_input_types', 'script_control_line', 'output_bit_registers0_to_31',
                                    'output_bit_registers32_to_63')},
    **{name: 'INT32' for name in ('robot_mode', 'safety_mode', 'safety_status', 'encoder0_raw', 'encoder1_raw',
                                   'tool_output_voltage', 'time_scale_source')},
    **{name: 'UINT8' for name in ('tool_output_mode', 'tool_digital_output0_mode', 'tool_digital_output1_mode')},
    'joint_mode': 'VECTOR6INT32',
    **_numbered('output_bit_register_', 64, 127, 'BOOL'), **_numbered('output_int_register_', 0, 47, 'INT32'),
    **_numbered('output_double_register_', 0, 47, 'DOUBLE'),
    **{name: kind for name, kind in INPUTS.items() if 'register' in name},  # input registers read back
}


class ProtocolError(UrSimError):
    """A package that does not follow the RTDE protocol (the connection is closed)."""


def package(kind: int, payload: bytes = b'') -> bytes:
    """One package: size, type, payload."""
    return HEADER.pack(HEADER.size + len(payload), kind) + payload


def recipe_format(types: Sequence[str]) -> struct.Struct:
    """The struct of a data package's values for a recipe of wire types (every one known)."""
    return struct.Struct('>' + ''.join(FORMATS[t] for t in types))


def flatten(values: Sequence) -> list:
    """Values of a recipe (scalars and vectors) as the flat list its struct packs."""
    out: list = []
    for v in values:
        if isinstance(v, (list, tuple)):
            out.extend(v)
        else:
            out.append(v)
    return out


def regroup(flat: Sequence, types: Sequence[str]) -> list:
    """The inverse of :func:`flatten`: vectors regrouped by the recipe's types."""
    out, i = [], 0
    for t in types:
        n = int(FORMATS[t][0]) if FORMATS[t][0].isdigit() else 1
        out.append(tuple(flat[i:i + n]) if n > 1 else flat[i])
        i += n
    return out


def text_message(message: str, source: str = 'ur_sim', level: int = 1) -> bytes:
    """A protocol-2 text message package (level: 0 exception, 1 error, 2 warning, 3 info)."""
    m, s = message.encode()[:255], source.encode()[:255]
    return package(TEXT_MESSAGE, bytes([len(m)]) + m + bytes([len(s)]) + s + bytes([level]))
