"""The real-time interface's package (TCP 30003 on a UR): the message size as a big-endian int32 (counting its own
4 bytes), then big-endian doubles, enums and bit masks included, in a fixed order that later software versions
extend at the end.

The values are the RTDE output variables of the same names (``rtde_fields.READERS``), so both interfaces report one
robot, with the same NaN for what ur_sim does not simulate (voltages, temperatures, the tool accelerometer,
the momentum, the controller's timer). The fields UR reserves for its own software are 0.
"""
from __future__ import annotations

import struct

from ur_sim_driver.ports.rtde_fields import CycleValues
from ur_sim_driver.robot.software import SoftwareVersion

# The layout in order: an RTDE variable (its value), or a number of reserved doubles (0.0).
LAYOUT: tuple[str | int, ...] = (
    'timestamp', 'target_q', 'target_qd', 'target_qdd', 'target_current', 'target_moment', 'actual_q', 'actual_qd',
    'actual_current', 'joint_control_output', 'actual_TCP_pose', 'actual_TCP_speed', 'actual_TCP_force',
    'target_TCP_pose', 'target_TCP_speed', 'actual_digital_input_bits', 'joint_temperatures', 'actual_execution_time',
    1,  # test value
    'robot_mode', 'joint_mode', 'safety_mode', 6, 'actual_tool_accelerometer', 6, 'speed_scaling', 'actual_momentum',
    2, 'actual_main_voltage', 'actual_robot_voltage', 'actual_robot_current', 'actual_joint_voltage',
    'actual_digital_output_bits', 'runtime_state',  # from 3.2
    'elbow_position', 'elbow_velocity',  # from 3.5 / 5.0
    'safety_status',  # from 3.10 / 5.4
    3,  # from 3.14 / 5.9
    'payload', 'payload_cog', 'payload_inertia',  # from 5.10
)


def package_size(version: SoftwareVersion) -> int:
    """[bytes] the package of a software version (CB3 3.x, e-Series and UR series 5.x; later versions as 5.10)."""
    v = (version.major, version.minor)
    if v[0] < 5:
        steps = ((3, 14), 1140), ((3, 10), 1116), ((3, 5), 1108), ((3, 2), 1060)
    else:
        steps = ((5, 10), 1220), ((5, 9), 1140), ((5, 4), 1116), ((5, 0), 1108)
    return next((size for since, size in steps if v >= since), 1044)


def _doubles(values: CycleValues) -> list[float]:
    out: list[float] = []
    for item in LAYOUT:
        if isinstance(item, int):
            out.extend([0.0] * item)
            continue
        value = values[item]
        out.extend(float(x) for x in value) if isinstance(value, tuple) else out.append(float(value))
    return out


def realtime_package(values: CycleValues, version: SoftwareVersion) -> bytes:
    """The package of the robot after the cycle just run (`values`), in the layout of `version` (call under the
    simulation lock)."""
    size = package_size(version)
    n = (size - 4) // 8
    return struct.pack(f'>i{n}d', size, *_doubles(values)[:n])
