"""URScript's functions that read the robot's state and kinematics, and the settings programs make before they move:
actual and target joints and TCP, the joint positions of earlier cycles, forward and inverse kinematics, the
safety limits, tool contact, the payload the robot believes in, and force mode's gain and damping. Poses are in the
robot's base frame (``base``, DH frame 0), the TCP at ``tool0``, as RTDE reports them; the TCP force as RTDE's
``actual_TCP_force`` (base axes, about the TCP). What they read goes through
the program's robot (``program.py``)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial.transform import Rotation

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.values import (
    REQUIRED,
    Pose,
    interpolate_pose,
    is_number,
    numbers,
    pose_argument,
    show,
)


def _in(name: str, value, low: float, high: float) -> float:
    if not is_number(value) or not low <= value <= high:
        raise ScriptError(f'{name} is a number in [{low:g}, {high:g}]; got {show(value)}')
    return float(value)


def _list(v: np.ndarray) -> list[float]:
    return [float(x) for x in v]


def pose_sub(p_from: Pose, p_to: Pose) -> Pose:
    """The inverse of ``pose_add``: positions subtracted, and p_to's rotation taken off p_from's."""
    r = Rotation.from_rotvec(p_to.values[3:]).inv() * Rotation.from_rotvec(p_from.values[3:])
    position = np.subtract(p_from.values[:3], p_to.values[:3])
    return Pose(tuple(float(v) for v in (*position, *r.as_rotvec())))


def state_functions(robot) -> dict[str, tuple[list, Callable]]:
    """name -> ([(argument, default or REQUIRED)], function), as ``builtins.builtins``."""
    R = REQUIRED

    def joints(name, q):
        return robot.actual_q() if q is None else np.array(numbers(name, q, 6))

    def forward_kin(q=None, tcp=None):
        if tcp is not None and not isinstance(tcp, Pose):
            raise ScriptError(f'get_forward_kin: tcp is a pose; got {show(tcp)}')
        return robot.forward_kin(joints('get_forward_kin: q', q), tcp)

    def has_solution(pose, qnear=None, maxPositionError=1e-10, maxOrientationError=1e-10):  # noqa: N803
        if not isinstance(pose, Pose):
            raise ScriptError(f'get_inverse_kin_has_solution: pose is a pose; got {show(pose)}')
        try:
            robot.inverse_kin(pose, None if qnear is None else _list(np.array(numbers('qnear', qnear, 6))))
        except ScriptError:
            return False
        return True

    def history(steps=0):
        if not isinstance(steps, int) or isinstance(steps, bool) or steps < 0:
            raise ScriptError(f'get_actual_joint_positions_history: steps is an integer >= 0; got {show(steps)}')
        return _list(robot.joint_history(steps))

    def within_limits(pose):
        """True when the joints (a list) or the IK of the pose (a pose) are within the joint limits."""
        if isinstance(pose, Pose):
            try:
                q = np.array(robot.inverse_kin(pose, None))
            except ScriptError:
                return False
        else:
            q = np.array(numbers('is_within_safety_limits: pose', pose, 6))
        return robot.within_joint_limits(q)

    def tool_contact(direction):
        return robot.tool_contact(np.array(numbers('tool_contact: direction', direction, 6)))

    def set_target_payload(m, cog, inertia=None, transition_time=0.0):
        inertia = np.zeros(6) if inertia is None else np.array(numbers('set_target_payload: inertia', inertia, 6))
        robot.set_payload(_in('set_target_payload: m', m, 0.0, 1e3), _list(np.array(numbers('set_target_payload: cog',
                                                                                     cog, 3))), _list(inertia))

    def gain_scaling(scaling):
        robot.force_settings['gain_scaling'] = _in('force_mode_set_gain_scaling: scaling', scaling, 0.0, 2.0)

    def damping(damping):
        robot.force_settings['damping'] = _in('force_mode_set_damping: damping', damping, 0.0, 1.0)

    return {
        'get_steptime': ([], lambda: robot.steptime()),
        # Not in the manual, but the controller knows it and the Client Library's External Control program calls it
        'get_joint_positions': ([], lambda: robot.joint_positions()),
        'get_tcp_force': ([], lambda: _list(robot.tcp_force())),
        'get_actual_joint_speeds': ([], lambda: _list(robot.actual_qd())),
        'get_target_joint_positions': ([], lambda: _list(robot.target_q())),
        'get_target_joint_speeds': ([], lambda: _list(robot.target_qd())),
        'get_actual_joint_positions_history': ([('steps', 0)], history),
        'get_target_tcp_pose': ([], lambda: robot.forward_kin(robot.target_q(), None)),
        'get_actual_tcp_speed': ([], lambda: _list(robot.tcp_speed(robot.actual_q(), robot.actual_qd()))),
        'get_target_tcp_speed': ([], lambda: _list(robot.tcp_speed(robot.target_q(), robot.target_qd()))),
        'get_actual_tool_flange_pose': ([], lambda: robot.forward_kin(robot.actual_q(), Pose((0.0,) * 6))),
        'get_forward_kin': ([('q', None), ('tcp', None)], forward_kin),
        'get_inverse_kin_has_solution': ([('pose', R), ('qnear', None), ('maxPositionError', 1e-10),
                                          ('maxOrientationError', 1e-10)], has_solution),
        'get_jacobian': ([('q', None), ('tcp', None)],
                         lambda q=None, tcp=None: [_list(row) for row in robot.jacobian(joints('get_jacobian: q', q))]),
        'is_within_safety_limits': ([('pose', R), ('qnear', None)], lambda pose, qnear=None: within_limits(pose)),
        'interpolate_pose': ([('p_from', R), ('p_to', R), ('alpha', R)],
                             lambda a, b, alpha: interpolate_pose(pose_argument('interpolate_pose: p_from', a),
                                                                  pose_argument('interpolate_pose: p_to', b),
                                                                  _in('interpolate_pose: alpha', alpha, -1e9, 1e9))),
        'pose_sub': ([('p_from', R), ('p_to', R)], lambda a, b: pose_sub(pose_argument('pose_sub: p_from', a),
                                                                         pose_argument('pose_sub: p_to', b))),
        'tool_contact': ([('direction', R)], tool_contact),
        'set_target_payload': ([('m', R), ('cog', R), ('inertia', None), ('transition_time', 0.0)],
                               set_target_payload),
        'get_target_payload': ([], lambda: robot.payload()[0]),
        'get_target_payload_cog': ([], lambda: robot.payload()[1]),
        'get_target_payload_inertia': ([], lambda: robot.payload()[2]),
        'get_target_joint_accelerations': ([], lambda: _list(robot.target_qdd())),
        'get_mass_matrix': ([], lambda: [_list(row) for row in robot.mass_matrix()]),
        'get_coriolis_and_centrifugal_torques': ([], lambda: _list(robot.coriolis())),
        'get_jacobian_time_derivative': ([], lambda: [_list(row) for row in robot.jacobian_rate(robot.actual_q(),
                                                                                                 robot.actual_qd())]),
        'get_tcp_offset': ([], lambda: robot.tcp_offset()),
        'set_tcp': ([('pose', R)], lambda pose: robot.set_tcp(pose_argument('set_tcp: pose', pose))),
        'is_steady': ([], lambda: robot.steady()),
        'get_target_waypoint': ([], lambda: robot.target_waypoint()),
        'get_joint_torques': ([], lambda: _list(robot.joint_torques())),
        'get_freedrive_status': ([], lambda: robot.freedrive_status()),
        'force_mode_set_gain_scaling': ([('scaling', R)], gain_scaling),
        'force_mode_set_damping': ([('damping', R)], damping),
    }

