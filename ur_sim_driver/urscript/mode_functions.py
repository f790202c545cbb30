"""URScript's functions that change how the robot behaves rather than where it goes: freedrive and teach mode (the
robot holds the arm up against gravity and lets it be pushed, as ``/freedrive_mode_controller`` does), the
force-torque sensor's zero, an external force-torque sensor fed through RTDE (``ft_rtde_input_enable``,
``robot/external_ft.py``), direct torque control (from PolyScope 5.23 / 10.10: ``robot/software.py``; friction
scales from 5.25.1 / 10.12.1), the gravity the controller believes in, a protective stop called by the program, force
mode (the robot's one force mode, ``motion/force_mode.py``, the same as ``/force_mode_controller``'s), and the end
and clearing of interpreter mode (``interpreter_session.py``; ``interpreter_mode()`` itself is the
interpreter's, as it runs statements).
What they do goes through the program's robot (``program.py``)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ur_sim_driver.errors import ConfigError, ScriptError
from ur_sim_driver.motion.force_mode import ForceModeSpec
from ur_sim_driver.robot.direct_torque import DEFAULT_SCALES, FrictionScales
from ur_sim_driver.robot.external_ft import make_external_ft
from ur_sim_driver.robot.software import FRICTION_SCALES, TORQUE_CONTROL, supports
from ur_sim_driver.urscript.values import REQUIRED, Pose, Request, is_number, numbers, show, truth

NO_COMPENSATION = FrictionScales.make([0.0] * 6, [0.0] * 6)  # direct_torque(friction_comp=False)

WATCHDOG_ACTIONS = ('ignore', 'pause', 'stop')


def _axes(value) -> list[int]:
    if not isinstance(value, list) or len(value) != 6 or not all(v in (0, 1) for v in value):
        raise ScriptError(f'freedrive_mode: freeAxes is a list of six 0 or 1; got {show(value)}')
    return [int(v) for v in value]


def mode_functions(robot) -> dict[str, tuple[list, Callable]]:
    """name -> ([(argument, default or REQUIRED)], function), as ``builtins.builtins``."""

    def freedrive_mode(freeAxes=None, feature=None):  # noqa: N803 (the manual's names)
        axes = _axes([1] * 6 if freeAxes is None else freeAxes)
        if feature is not None and not isinstance(feature, Pose):
            raise ScriptError(f'freedrive_mode: feature is a pose; got {show(feature)}')
        if axes != [1] * 6:
            raise ScriptError('freedrive_mode: ur_sim frees all six axes only (freeAxes [1, 1, 1, 1, 1, 1]); '
                              f'got {axes}')
        robot.set_free(True)

    def set_gravity(d):
        if not isinstance(d, list) or len(d) != 3 or not all(is_number(v) for v in d):
            raise ScriptError(f'set_gravity: d is a list of 3 numbers [m/s^2]; got {show(d)}')
        robot.set_gravity([float(v) for v in d])

    def force_mode(task_frame, selection_vector, wrench, type, limits):  # noqa: A002 (the manual's name)
        if not isinstance(task_frame, Pose):
            raise ScriptError(f'force_mode: task_frame is a pose; got {show(task_frame)}')
        selection = numbers('force_mode: selection_vector', selection_vector)
        if not all(v in (0, 1) for v in selection):
            raise ScriptError(f'force_mode: selection_vector is six 0 or 1; got {show(selection_vector)}')
        if type not in (1, 2, 3):
            raise ScriptError(f'force_mode: type is 1, 2 or 3; got {show(type)}')
        bounds = np.abs(numbers('force_mode: limits', limits))
        wrench = np.array(numbers('force_mode: wrench', wrench))
        robot.set_force_mode(ForceModeSpec(task_frame.matrix(), np.array(selection, bool), wrench, int(type), bounds,
                                           0.0, 0.0))

    def direct_torque(torque, friction_comp=True, viscous_scale=None, coulomb_scale=None):
        torques = np.array(numbers('direct_torque: torque', torque))
        if viscous_scale is not None or coulomb_scale is not None:  # PolyScope 5.25.1 / 10.12.1
            scales = FrictionScales.make(
                _scales('viscous_scale', DEFAULT_SCALES.viscous if viscous_scale is None else viscous_scale),
                _scales('coulomb_scale', DEFAULT_SCALES.coulomb if coulomb_scale is None else coulomb_scale))
        else:  # the robot's default compensation, or none
            scales = DEFAULT_SCALES if truth(friction_comp) else NO_COMPENSATION
        robot.direct_torque(torques, scales)
        return Request('sync')  # it holds the thread until the next control cycle, as the robot's does

    def ft_input(name):
        def enable(enable, sensor_mass=0.0, sensor_measuring_offset=None, sensor_cog=None):
            if not truth(enable):
                robot.enable_external_ft(None)
                return
            values = [numbers(f'{name}: {arg}', v, 3) if v is not None else [0.0, 0.0, 0.0]
                      for arg, v in (('sensor_measuring_offset', sensor_measuring_offset), ('sensor_cog', sensor_cog))]
            if not is_number(sensor_mass):
                raise ScriptError(f'{name}: sensor_mass is a number [kg]; got {show(sensor_mass)}')
            try:
                robot.enable_external_ft(make_external_ft(float(sensor_mass), *values))
            except ConfigError as e:
                raise ScriptError(f'{name}: {e}') from None
        return [('enable', REQUIRED), ('sensor_mass', 0.0), ('sensor_measuring_offset', None),
                ('sensor_cog', None)], enable

    def watchdog(variable_name, min_frequency, action='pause'):
        if not isinstance(variable_name, str) or not variable_name:
            raise ScriptError('rtde_set_watchdog: variable_name is the name of an RTDE input; got '
                              f'{show(variable_name)}')
        if not is_number(min_frequency) or min_frequency < 0:
            raise ScriptError(f'rtde_set_watchdog: min_frequency is a number >= 0 [Hz]; got {show(min_frequency)}')
        if action not in WATCHDOG_ACTIONS:
            raise ScriptError(f'rtde_set_watchdog: action is one of {", ".join(WATCHDOG_ACTIONS)}; got {show(action)}')
        robot.set_watchdog(variable_name, float(min_frequency), action)

    def clear_interpreter():
        session = robot.interpreter_session()
        if not session.active:
            raise ScriptError('clear_interpreter() can only be called in interpreter mode')
        session.clear()

    version = robot.software_version()
    table = {
        'ft_rtde_input_enable': ft_input('ft_rtde_input_enable'),
        'enable_external_ft_sensor': ft_input('enable_external_ft_sensor'),  # its older name
        'rtde_set_watchdog': ([('variable_name', REQUIRED), ('min_frequency', REQUIRED), ('action', 'pause')],
                              watchdog),
        'force_mode': ([('task_frame', REQUIRED), ('selection_vector', REQUIRED), ('wrench', REQUIRED),
                        ('type', REQUIRED), ('limits', REQUIRED)], force_mode),
        'end_force_mode': ([], lambda: robot.set_force_mode(None)),
        'end_interpreter': ([], lambda: robot.interpreter_session().end()),
        'clear_interpreter': ([], clear_interpreter),
        'freedrive_mode': ([('freeAxes', None), ('feature', None)], freedrive_mode),
        'end_freedrive_mode': ([], lambda: robot.set_free(False)),
        'teach_mode': ([], lambda: robot.set_free(True)),
        'end_teach_mode': ([], lambda: robot.set_free(False)),
        'zero_ftsensor': ([], lambda: robot.zero_ftsensor()),
        'set_gravity': ([('d', REQUIRED)], set_gravity),
        'protective_stop': ([], lambda: robot.protective_stop()),
    }
    if supports(version, TORQUE_CONTROL):
        arguments = [('torque', REQUIRED), ('friction_comp', True)]
        if supports(version, FRICTION_SCALES):
            arguments += [('viscous_scale', None), ('coulomb_scale', None)]
        table['direct_torque'] = (arguments, direct_torque)
    return table


def _scales(name: str, value) -> list[float]:
    """Six friction compensation scales, each in [0, 1]."""
    scales = numbers(f'direct_torque: {name}', value if not isinstance(value, np.ndarray) else value.tolist(), 6)
    if not all(0.0 <= v <= 1.0 for v in scales):
        raise ScriptError(f'direct_torque: {name} is six numbers in [0, 1]; got {show(value)}')
    return scales
