"""ur_rtde's control script, recognised and run natively: the register protocol of ``RTDEControlInterface``
(ur_rtde 1.6, PyPI ``ur-rtde``).

``RTDEControlInterface`` uploads a URScript program ``rtde_control`` of about 1300 lines, with threads, on the
real-time port, then drives the robot through RTDE registers. ur_sim's URScript subset has no threads, so a program
that carries that script's signature (:func:`recognises`) is run by this loop instead, which keeps the script's
protocol:

* ``input_int_register_0`` (plus the script's register offset, 0 or 24) holds the command; the parameters are in
  ``input_double_register_0..`` and ``input_int_register_1``.
* ``output_int_register_0`` is 1 (ready for a command) or 2 (done with it). A command runs once, then 2 until the
  client writes 0 (no command), then 1 again. Streamed commands (servoJ, speedJ, speedL) are applied again every
  cycle while the register holds them, with no handshake.
* ``output_int_register_2`` reports an asynchronous move: bits 24-30 the operation's number, 16-23 a write count,
  bit 15 running.
* Stop script (255) ends the program; runtime_state then leaves PLAYING, which the client waits for.

Commands run: moveJ, moveJ_IK, moveL, moveL_FK (each also asynchronous), speedJ, speedL, servoJ, speedStop,
servoStop, stopJ, stopL (each also asynchronous), moveUntilContact, setPayload, stopScript. Any other command is a
runtime error that names it, and the program stops, as a failing script stops on the robot. The moves are the
URScript moves of ``program.py``, so they obey the same limits, speed scaling and safety.
"""
from __future__ import annotations

import re
from collections.abc import Iterator

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.threads import Threads
from ur_sim_driver.urscript.values import Pose, Request

NAME = 'rtde_control'
SIGNATURE = ('def rtde_control():', '# HEADER_BEGIN', '# NODE_CONTROL_LOOP_BEGINS', 'RTDE Control Script Loaded')
READY, DONE = 1, 2  # output_int_register_0
RUNNING_BIT = 1 << 15  # output_int_register_2: an asynchronous operation runs
# ur_rtde's command numbers (RobotCommand::Type), for the messages.
COMMANDS = {
    0: 'NO_CMD', 1: 'MOVEJ', 2: 'MOVEJ_IK', 3: 'MOVEL', 4: 'MOVEL_FK', 6: 'FORCE_MODE', 7: 'FORCE_MODE_STOP',
    8: 'ZERO_FT_SENSOR', 9: 'SPEEDJ', 10: 'SPEEDL', 11: 'SERVOJ', 12: 'SERVOC', 13: 'SET_STD_DIGITAL_OUT',
    14: 'SET_TOOL_DIGITAL_OUT', 15: 'SPEED_STOP', 16: 'SERVO_STOP', 17: 'SET_PAYLOAD', 18: 'TEACH_MODE',
    19: 'END_TEACH_MODE', 20: 'FORCE_MODE_SET_DAMPING', 21: 'FORCE_MODE_SET_GAIN_SCALING', 22: 'SET_SPEED_SLIDER',
    23: 'SET_STD_ANALOG_OUT', 24: 'SERVOL', 25: 'TOOL_CONTACT', 26: 'GET_STEPTIME',
    27: 'GET_ACTUAL_JOINT_POSITIONS_HISTORY', 28: 'GET_TARGET_WAYPOINT', 29: 'SET_TCP',
    30: 'GET_INVERSE_KINEMATICS_ARGS', 31: 'PROTECTIVE_STOP', 33: 'STOPL', 34: 'STOPJ', 35: 'SET_WATCHDOG',
    36: 'IS_POSE_WITHIN_SAFETY_LIMITS', 37: 'IS_JOINTS_WITHIN_SAFETY_LIMITS', 38: 'GET_JOINT_TORQUES',
    39: 'POSE_TRANS', 40: 'GET_TCP_OFFSET', 41: 'JOG_START', 42: 'JOG_STOP', 43: 'GET_FORWARD_KINEMATICS_DEFAULT',
    44: 'GET_FORWARD_KINEMATICS_ARGS', 45: 'MOVE_PATH', 46: 'GET_INVERSE_KINEMATICS_DEFAULT', 47: 'IS_STEADY',
    48: 'SET_CONF_DIGITAL_OUT', 49: 'SET_INPUT_INT_REGISTER', 50: 'SET_INPUT_DOUBLE_REGISTER',
    51: 'MOVE_UNTIL_CONTACT', 52: 'FREEDRIVE_MODE', 53: 'END_FREEDRIVE_MODE', 54: 'GET_FREEDRIVE_STATUS',
    55: 'SET_EXTERNAL_FORCE_TORQUE', 56: 'FT_RTDE_INPUT_ENABLE', 57: 'ENABLE_EXTERNAL_FT_SENSOR',
    58: 'GET_ACTUAL_TOOL_FLANGE_POSE', 59: 'SET_GRAVITY', 60: 'GET_IK_HAS_SOLUTION_DEFAULT',
    61: 'GET_IK_HAS_SOLUTION_ARGS', 62: 'START_CONTACT_DETECTION', 63: 'STOP_CONTACT_DETECTION',
    64: 'READ_CONTACT_DETECTION', 65: 'SET_TARGET_PAYLOAD', 66: 'DIRECT_TORQUE', 67: 'GET_MASS_MATRIX',
    68: 'GET_CORIOLIS_AND_CENTRIFUGAL_TORQUES', 69: 'GET_TARGET_JOINT_ACCELERATIONS', 70: 'GET_JACOBIAN',
    71: 'GET_JACOBIAN_TIME_DERIVATIVE', 255: 'STOP_SCRIPT',
}
MOVES = (1, 2, 3, 4)
SPEEDJ, SPEEDL, SERVOJ = 9, 10, 11
# The script applies these again every cycle while the register holds them (its "real-time" commands).
STREAMED = frozenset((6, 9, 10, 11, 24, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71))
SPEED_STOP, SERVO_STOP, SET_PAYLOAD, STOPL, STOPJ, MOVE_UNTIL_CONTACT, STOP_SCRIPT = 15, 16, 17, 33, 34, 51, 255
CONTACT_STOP = 3.0  # [m/s^2] moveUntilContact's stop on a contact (the script's stopl(3))
_OFFSET = re.compile(r'#\s*(float|int) register offset\s*\n\s*(\d+)')


def recognises(source: str) -> bool:
    """Whether `source` is ur_rtde's control script (its first line and its section markers)."""
    return source.lstrip().startswith(SIGNATURE[0]) and all(mark in source for mark in SIGNATURE[1:])


class RtdeControlLoop:
    """Stands in for the URScript interpreter of a ``ScriptProgram``: :meth:`run` yields the program's requests.

    Args:
        source: the uploaded script (its register offsets are read from it: 0, or 24 for the upper range).
        robot: the program's robot (``ScriptProgram``), read and changed under the simulation lock.
    """

    name = NAME
    secondary = False
    line = column = 0  # no URScript line: a runtime error points nowhere

    def __init__(self, source: str, robot) -> None:
        offsets = {kind: int(n) for kind, n in _OFFSET.findall(source)}
        self.float_offset, self.int_offset = offsets.get('float', 0), offsets.get('int', 0)
        self.robot = robot
        self._async_id = 0
        self._async_writes = 0
        self._async = False  # an asynchronous move or stop runs
        self._stop_type = 'stopj'  # the script's stop_type: set to stopl only by an asynchronous stop
        self._speed_type = 'speedj'
        self.threads = Threads()  # one: the loop
        self.threads.start(NAME, self.run)

    # ---- registers --------------------------------------------------------------------------------------------
    def _int(self, i: int) -> int:
        return int(self._regs.input_ints[self.int_offset + i])

    def _doubles(self, first: int, n: int) -> list[float]:
        k = self.float_offset + first
        return [float(v) for v in self._regs.input_doubles[k:k + n]]

    def _signal(self, value: int) -> None:
        self._regs.output_ints[self.int_offset] = value

    def _progress(self, value: int) -> None:
        """output_int_register_2: an asynchronous operation started (0), at a step (> 0) or finished (-1)."""
        self._async_writes = (self._async_writes + 1) % 128
        if value == 0:
            self._async_id = (self._async_id + 1) % 128
        word = self._async_writes << 16 | self._async_id << 24
        if value >= 0:
            word |= min(value, 32767) | RUNNING_BIT
        self._regs.output_ints[self.int_offset + 2] = word

    # ---- the loop ---------------------------------------------------------------------------------------------
    def run(self) -> Iterator[Request]:
        self._regs = self.robot.registers()
        self.robot.textmsg('ur_rtde control script: its register protocol runs natively in ur_sim')
        self._progress(-1)
        self._signal(READY)
        executing = False
        while True:
            if self._async and self.robot.move_finished():
                self._async = False
                self._progress(-1)
            cmd = self._int(0)
            if cmd in STREAMED:
                self._cancel_async()
                yield Request('start', self._streamed(cmd))
                self._signal(READY)
            elif cmd == 0:
                executing = False
                self._signal(READY)
            elif not executing:
                executing = True
                if cmd == STOP_SCRIPT:
                    self.robot.textmsg('Received stop script!')
                    return
                yield from self._process(cmd)
                self._signal(DONE)
            yield Request('sync')

    def _streamed(self, cmd: int) -> tuple:
        if cmd == SPEEDJ or cmd == SPEEDL:
            target, (a, _t) = self._doubles(0, 6), self._doubles(6, 2)
            self._speed_type = 'speedj' if cmd == SPEEDJ else 'speedl'
            # applied again every cycle: its time only bounds one call, so none is given
            return ('speedj', target, a, None) if cmd == SPEEDJ else ('speedl', target, a, None, None)
        if cmd == SERVOJ:
            q, (_v, _a, t, lookahead, gain) = self._doubles(0, 6), self._doubles(6, 5)
            return 'servoj', q, 0.0, 0.0, t, lookahead, gain
        raise ScriptError(self._unsupported(cmd))

    def _process(self, cmd: int) -> Iterator[Request]:
        if cmd in MOVES:
            yield from self._move(cmd)
        elif cmd in (STOPJ, STOPL):
            yield from self._stop()
        elif cmd == SPEED_STOP:
            self._cancel_async()
            yield Request('move', ('stopl', self._doubles(0, 1)[0], None) if self._speed_type == 'speedl'
                          else ('stopj', self._doubles(0, 1)[0]))
        elif cmd == SERVO_STOP:
            self._cancel_async()
            yield Request('move', ('stopl', self._doubles(0, 1)[0], None))
        elif cmd == SET_PAYLOAD:
            mass, *cog = self._doubles(0, 4)
            self.robot.set_payload(mass, cog if any(cog) else self.robot.payload_cog())
        elif cmd == MOVE_UNTIL_CONTACT:
            yield from self._until_contact()
        else:
            raise ScriptError(self._unsupported(cmd))

    def _move(self, cmd: int) -> Iterator[Request]:
        values, (v, a) = self._doubles(0, 6), self._doubles(6, 2)
        self._cancel_async()
        if cmd == 2:  # moveJ_IK: the pose's joints nearest the present ones
            values = self.robot.inverse_kin(Pose(tuple(values)), None)
        target = Pose(tuple(values)) if cmd == 3 else values
        move = ('movej' if cmd in (1, 2) else 'movel', target, a, v, 0.0, 0.0)
        if self._int(1) == 1:
            yield Request('start', move)
            self._async = True
            self._progress(0)
        else:
            yield Request('move', move)

    def _stop(self) -> Iterator[Request]:
        decel = self._doubles(0, 1)[0]
        self._cancel_async()
        if self._int(1) == 1:
            self._stop_type = 'stopl'  # as the script: an asynchronous stop is a stopl, and later ones are too
            yield Request('start', ('stopl', decel, None))
            self._async = True
            self._progress(0)
        else:
            yield Request('move', ('stopl', decel, None) if self._stop_type == 'stopl' else ('stopj', decel))

    def _cancel_async(self) -> None:
        if self._async:
            self._async = False
            self._progress(-1)

    def _until_contact(self) -> Iterator[Request]:
        """speedl along the tool speed until the tool touches something, then stop and go back to where the contact
        began. The direction argument is not used: any tool contact counts."""
        xd, a = self._doubles(0, 6), self._doubles(12, 1)[0]
        while not self.robot.tool_touch():
            yield Request('start', ('speedl', xd, a, None, None))
            yield Request('sync')
        touched = self.robot.joint_positions()
        yield Request('move', ('stopl', CONTACT_STOP, None))
        yield Request('move', ('movel', touched, 1.2, 0.25, 0.0, 0.0))

    @staticmethod
    def _unsupported(cmd: int) -> str:
        runs = ', '.join(COMMANDS[c] for c in (*MOVES, SPEEDJ, SPEEDL, SERVOJ, SPEED_STOP, SERVO_STOP, STOPJ, STOPL,
                                               MOVE_UNTIL_CONTACT, SET_PAYLOAD, STOP_SCRIPT))
        return (f'ur_rtde command {cmd} ({COMMANDS.get(cmd, "unknown")}) is not run by ur_sim; its native '
                f'control loop runs {runs}')
