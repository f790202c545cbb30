"""The functions a URScript program can call, besides its own: name -> (arguments with their defaults, function).
Each checks its arguments (a ScriptError names the function, the argument, the value and the limit); a function
that needs robot time returns a Request that the interpreter yields. What they do to the robot goes through the
interpreter's ScriptRobot."""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.robot.io_bank import tool_voltage_refusal
from ur_sim_driver.robot.registers import N_BITS, N_DOUBLES, N_INTS
from ur_sim_driver.robot.software import OPTIMOVE, supports
from ur_sim_driver.urscript.mode_functions import mode_functions
from ur_sim_driver.urscript.socket_functions import socket_functions
from ur_sim_driver.urscript.state_functions import state_functions
from ur_sim_driver.urscript.values import (
    REQUIRED,
    Pose,
    Request,
    ThreadHandle,
    is_number,
    numbers,
    pose_add,
    pose_argument,
    pose_dist,
    pose_inv,
    pose_trans,
    show,
    truth,
)


def _number(name: str, value, low: float = -math.inf, high: float = math.inf) -> float:
    if not is_number(value) or not math.isfinite(value):
        raise ScriptError(f'{name} is a finite number; got {show(value)}')
    if not low <= value <= high:
        raise ScriptError(f'{name} = {show(value)} is outside [{low:g}, {high:g}]')
    return float(value)


def _integer(name: str, value, low: int, high: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        raise ScriptError(f'{name} is an integer in [{low}, {high}]; got {show(value)}')
    return value


def builtins(robot) -> dict[str, tuple[list, Callable]]:
    """name -> ([(argument, default or _REQUIRED)], function)."""
    R = REQUIRED

    def move(kind):
        return lambda *args: Request('move', (kind, *args))

    def digital(name, offset, count):
        def set_out(n, b):
            robot.set_digital_out(offset + _integer(f'{name}: n', n, 0, count - 1), truth(b))
        return set_out

    def register(kind, side, write=False):
        size = {'integer': N_INTS, 'float': N_DOUBLES, 'boolean': N_BITS}[kind]
        attr = {'integer': 'ints', 'float': 'doubles', 'boolean': 'bits'}[kind]
        cast = {'integer': lambda v: int(_number('value', v)), 'float': lambda v: _number('value', v),
                'boolean': truth}[kind]
        verb = 'write' if write else 'read'
        label = f'{verb}_{side}_{kind}_register'
        if write:
            def write_register(n, value):
                getattr(robot.registers(), f'{side}_{attr}')[_integer(f'{label}: address', n, 0, size - 1)] = \
                    cast(value)
            return [('address', R), ('value', R)], write_register
        return [('address', R)], lambda n: getattr(robot.registers(), f'{side}_{attr}')[
            _integer(f'{label}: address', n, 0, size - 1)]

    def textmsg(s1, s2=''):
        robot.textmsg(show(s1) + show(s2))

    def set_analog(n, f):
        robot.set_analog_out(_integer('set_analog_out: n', n, 0, 1), _number('set_analog_out: f', f, 0.0, 1.0))

    def set_payload(m, cog=None):
        robot.set_payload(_number('set_payload: m', m, 0.0), numbers('set_payload: cog', cog, 3) if cog is not None
                          else [0.0, 0.0, 0.0])

    def inverse_kin(x, qnear=None, maxPositionError=1e-10, maxOrientationError=1e-10, tcp=None):  # noqa: N803
        return robot.inverse_kin(pose_argument('get_inverse_kin: x', x),
                                 None if qnear is None else numbers('get_inverse_kin: qnear', qnear))

    def sleep(t):
        return Request('sleep', (_number('sleep: t', t, 0.0),))

    def norm(a):
        if isinstance(a, (list, Pose)):
            return float(np.linalg.norm(numbers('norm: a', a, len(a.values if isinstance(a, Pose) else a))))
        return abs(_number('norm: a', a))

    def text(name: str, value) -> str:
        if isinstance(value, ThreadHandle):
            raise ScriptError(f'{name}: a thread handle has no text')
        return show(value)

    def list_length(v):
        if not isinstance(v, (list, Pose)):
            raise ScriptError(f'get_list_length: v is a list; got {show(v)}')
        return len(v.values if isinstance(v, Pose) else v)

    def popup(s, title='Popup', warning=False, error=False, blocking=False):
        # No one can press a button on a simulated teach pendant: the message goes to the log and the program goes
        # on, even when `blocking` asks it to wait.
        level = 'error' if truth(error) else 'warning' if truth(warning) else 'message'
        robot.textmsg(f'popup ({level}) {show(title)}: {show(s)}')

    def tool_voltage(voltage):
        refusal = tool_voltage_refusal(voltage) if is_number(voltage) else 'a number of volts: 0, 12 or 24'
        if refusal is not None:
            raise ScriptError(f'set_tool_voltage: voltage {show(voltage)}: {refusal}')
        robot.set_tool_voltage(int(voltage))

    table = {
        'str_cat': ([('op1', R), ('op2', R)], lambda a, b: text('str_cat', a) + text('str_cat', b)),
        'to_str': ([('val', R)], lambda v: text('to_str', v)),
        'get_list_length': ([('v', R)], list_length),
        'popup': ([('s', R), ('title', 'Popup'), ('warning', False), ('error', False), ('blocking', False)], popup),
        'set_tool_voltage': ([('voltage', R)], tool_voltage),
        'movej': ([('q', R), ('a', 1.4), ('v', 1.05), ('t', 0.0), ('r', 0.0)], move('movej')),
        'movel': ([('pose', R), ('a', 1.2), ('v', 0.25), ('t', 0.0), ('r', 0.0)], move('movel')),
        'speedj': ([('qd', R), ('a', R), ('t', None)], move('speedj')),
        'stopj': ([('a', R)], move('stopj')),
        'speedl': ([('xd', R), ('a', R), ('t', None), ('aRot', None)], move('speedl')),
        'stopl': ([('a', R), ('aRot', None)], move('stopl')),
        'servoj': ([('q', R), ('a', 0.0), ('v', 0.0), ('t', 0.002), ('lookahead_time', 0.1), ('gain', 300.0)],
                   move('servoj')),
        'servoc': ([('pose', R), ('a', 1.2), ('v', 0.25), ('r', 0.0)], move('servoc')),
        'movep': ([('pose', R), ('a', 1.2), ('v', 0.25), ('r', 0.0)], move('movep')),
        'movec': ([('pose_via', R), ('pose_to', R), ('a', 1.2), ('v', 0.25), ('r', 0.0), ('mode', 0)],
                  move('movec')),
        'sleep': ([('t', R)], sleep),
        'sync': ([], lambda: Request('sync')),
        'textmsg': ([('s1', R), ('s2', '')], textmsg),
        'set_digital_out': ([('n', R), ('b', R)], digital('set_digital_out', 0, 8)),
        'set_standard_digital_out': ([('n', R), ('b', R)], digital('set_standard_digital_out', 0, 8)),
        'set_configurable_digital_out': ([('n', R), ('b', R)], digital('set_configurable_digital_out', 8, 8)),
        'set_tool_digital_out': ([('n', R), ('b', R)], digital('set_tool_digital_out', 16, 2)),
        'set_analog_out': ([('n', R), ('f', R)], set_analog),
        'set_standard_analog_out': ([('n', R), ('f', R)], set_analog),
        'get_standard_digital_in': ([('n', R)], lambda n: robot.digital_in(_integer('n', n, 0, 7))),
        'get_standard_digital_out': ([('n', R)], lambda n: robot.digital_out(_integer('n', n, 0, 7))),
        'get_configurable_digital_in': ([('n', R)], lambda n: robot.digital_in(8 + _integer('n', n, 0, 7))),
        'get_configurable_digital_out': ([('n', R)], lambda n: robot.digital_out(8 + _integer('n', n, 0, 7))),
        'get_tool_digital_in': ([('n', R)], lambda n: robot.digital_in(16 + _integer('n', n, 0, 1))),
        'get_tool_digital_out': ([('n', R)], lambda n: robot.digital_out(16 + _integer('n', n, 0, 1))),
        'set_payload': ([('m', R), ('cog', None)], set_payload),
        'get_actual_joint_positions': ([], lambda: robot.joint_positions()),
        'get_actual_tcp_pose': ([], lambda: robot.tcp_pose()),
        'get_inverse_kin': ([('x', R), ('qnear', None), ('maxPositionError', 1e-10),
                             ('maxOrientationError', 1e-10), ('tcp', None)], inverse_kin),
        'pose_trans': ([('p_from', R), ('p_from_to', R)],
                       lambda a, b: pose_trans(pose_argument('pose_trans: p_from', a),
                                               pose_argument('pose_trans: p_from_to', b))),
        'pose_inv': ([('p_from', R)], lambda a: pose_inv(pose_argument('pose_inv: p_from', a))),
        'pose_add': ([('p_1', R), ('p_2', R)], lambda a, b: pose_add(pose_argument('pose_add: p_1', a),
                                                                     pose_argument('pose_add: p_2', b))),
        'pose_dist': ([('p_from', R), ('p_to', R)], lambda a, b: pose_dist(pose_argument('pose_dist: p_from', a),
                                                                           pose_argument('pose_dist: p_to', b))),
        'norm': ([('a', R)], norm),
        'sqrt': ([('f', R)], lambda f: math.sqrt(_number('sqrt: f', f, 0.0))),
        'sin': ([('f', R)], lambda f: math.sin(_number('sin: f', f))),
        'cos': ([('f', R)], lambda f: math.cos(_number('cos: f', f))),
        'tan': ([('f', R)], lambda f: math.tan(_number('tan: f', f))),
        'asin': ([('f', R)], lambda f: math.asin(_number('asin: f', f, -1.0, 1.0))),
        'acos': ([('f', R)], lambda f: math.acos(_number('acos: f', f, -1.0, 1.0))),
        'atan': ([('f', R)], lambda f: math.atan(_number('atan: f', f))),
        'atan2': ([('y', R), ('x', R)], lambda y, x: math.atan2(_number('atan2: y', y), _number('atan2: x', x))),
        'pow': ([('base', R), ('exponent', R)], lambda b, e: math.pow(_number('pow: base', b),
                                                                       _number('pow: exponent', e))),
        'fabs': ([('f', R)], lambda f: abs(_number('fabs: f', f))),
        'floor': ([('f', R)], lambda f: int(math.floor(_number('floor: f', f)))),
        'ceil': ([('f', R)], lambda f: int(math.ceil(_number('ceil: f', f)))),
        'd2r': ([('d', R)], lambda d: math.radians(_number('d2r: d', d))),
        'r2d': ([('r', R)], lambda r: math.degrees(_number('r2d: r', r))),
    }
    for kind in ('integer', 'float', 'boolean'):
        for side in ('input', 'output'):
            table[f'read_{side}_{kind}_register'] = register(kind, side)
        table[f'write_output_{kind}_register'] = register(kind, 'output', write=True)
    if supports(robot.software_version(), OPTIMOVE):
        table['optimovej'] = ([('q', R), ('a', 0.3), ('v', 0.3), ('r', 0.0)], move('optimovej'))
        table['optimovel'] = ([('pose', R), ('a', 0.3), ('v', 0.3), ('r', 0.0)], move('optimovel'))
    table.update(socket_functions(robot))
    table.update(state_functions(robot))
    table.update(mode_functions(robot))
    return table
