"""The robot's modes and program state as a real UR controller keeps them, without ROS.

Robot mode (ur_dashboard_msgs/RobotMode values): POWER_OFF -> power on -> POWER_ON -> IDLE -> brake release ->
RUNNING. A brake release while powered off powers the robot on first (as the real robot does). Safety mode
(SafetyMode values): NORMAL, PROTECTIVE_STOP, ... Program state: STOPPED, PLAYING, PAUSED, of the loaded program.
The driver's ``robot_program_running`` is true while the External Control program (the driver's URCap program)
plays; another program playing leaves it false, as on the robot.

Motion is possible only when RUNNING, NORMAL and the External Control program plays; :meth:`RobotState.
motion_refusal` names what is missing. The transitions that take time on a robot (powering on, releasing the
brakes) take :data:`POWER_ON_TIME` and :data:`BRAKE_RELEASE_TIME` of simulated time here; :meth:`update`
advances them. Methods that a dashboard command maps to return None when done or a reason when refused.
"""
from __future__ import annotations

import posixpath
from dataclasses import dataclass

from ur_sim_driver.robot.registers import Registers

# ur_dashboard_msgs/RobotMode
NO_CONTROLLER, DISCONNECTED, CONFIRM_SAFETY, BOOTING, POWER_OFF, POWER_ON, IDLE, BACKDRIVE, RUNNING = range(-1, 8)
ROBOT_MODE_NAMES = {NO_CONTROLLER: 'NO_CONTROLLER', DISCONNECTED: 'DISCONNECTED', CONFIRM_SAFETY: 'CONFIRM_SAFETY',
                    BOOTING: 'BOOTING', POWER_OFF: 'POWER_OFF', POWER_ON: 'POWER_ON', IDLE: 'IDLE',
                    BACKDRIVE: 'BACKDRIVE', RUNNING: 'RUNNING'}
# ur_dashboard_msgs/SafetyMode
NORMAL, REDUCED, PROTECTIVE_STOP, RECOVERY, SAFEGUARD_STOP = 1, 2, 3, 4, 5
SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP, VIOLATION, FAULT = 6, 7, 8, 9
SAFETY_MODE_NAMES = {NORMAL: 'NORMAL', REDUCED: 'REDUCED', PROTECTIVE_STOP: 'PROTECTIVE_STOP',
                     RECOVERY: 'RECOVERY', SAFEGUARD_STOP: 'SAFEGUARD_STOP',
                     SYSTEM_EMERGENCY_STOP: 'SYSTEM_EMERGENCY_STOP', ROBOT_EMERGENCY_STOP: 'ROBOT_EMERGENCY_STOP',
                     VIOLATION: 'VIOLATION', FAULT: 'FAULT'}
# ur_dashboard_msgs/ProgramState
STOPPED, PLAYING, PAUSED = 'STOPPED', 'PLAYING', 'PAUSED'

POWER_ON_TIME = 0.5  # [s] of simulated time from power on to IDLE (a robot takes a few seconds)
BRAKE_RELEASE_TIME = 0.5  # [s] from brake release to RUNNING
UNLOCK_DELAY = 5.0  # [s] after a protective stop before it may be unlocked (the robot's rule)
EXTERNAL_CONTROL_PROGRAM = 'external_control.urp'
PROGRAM_DIR = '/programs'  # where an e-series controller keeps its programs


@dataclass(frozen=True)
class RobotStatus:
    """A snapshot of the robot's state (what io_and_status_controller publishes)."""

    robot_mode: int
    safety_mode: int
    program_state: str
    loaded_program: str
    program_running: bool


class RobotState:
    """Robot mode, safety mode and program state, advanced with simulated time.

    Args:
        powered_off: start POWER_OFF with the program stopped (else RUNNING, NORMAL, External Control playing).
        programs: program files that exist on the simulated robot besides the External Control program,
            as file names in :data:`PROGRAM_DIR` (e.g. 'wait_program.urp').
    """

    def __init__(self, powered_off: bool = False, programs: tuple[str, ...] = ()) -> None:
        self.robot_mode = POWER_OFF if powered_off else RUNNING
        self.safety_mode = NORMAL
        self.program_state = STOPPED if powered_off else PLAYING
        self.loaded_program = EXTERNAL_CONTROL_PROGRAM
        self.programs = tuple(dict.fromkeys((EXTERNAL_CONTROL_PROGRAM, *programs)))
        self.stop_time: float | None = None  # [s] when the last protective stop happened
        self.stop_cause = ''
        self._pending: list[tuple[float, int]] = []  # (time [s], mode) steps of a transition under way
        self._now = 0.0
        self.registers = Registers()  # the general purpose registers (RTDE, URScript)
        self.rtde_inputs: dict[str, float] = {}  # [s] of robot time each RTDE input variable was last written
        self.script: str | None = None  # the URScript program playing instead of the loaded one (its name)

    # ---- queries ------------------------------------------------------------------------------
    def status(self) -> RobotStatus:
        return RobotStatus(self.robot_mode, self.safety_mode, self.program_state, self.loaded_program,
                           self.program_running)

    @property
    def now(self) -> float:
        """[s] simulated time of the last :meth:`update` (or protective stop)."""
        return self._now

    @property
    def program_running(self) -> bool:
        """The driver's robot_program_running: the External Control program is playing."""
        return (self.program_state == PLAYING and self.loaded_program == EXTERNAL_CONTROL_PROGRAM
                and self.script is None)

    @property
    def loaded_program_path(self) -> str:
        """The loaded program's full path on the controller, e.g. '/programs/external_control.urp'."""
        return posixpath.join(PROGRAM_DIR, self.loaded_program)

    def motion_refusal(self) -> str | None:
        """None when the robot can move, else why not (names the state)."""
        if self.safety_mode != NORMAL:
            cause = f' ({self.stop_cause})' if self.safety_mode == PROTECTIVE_STOP and self.stop_cause else ''
            return f'safety mode is {SAFETY_MODE_NAMES[self.safety_mode]}{cause}; motion needs NORMAL'
        if self.robot_mode != RUNNING:
            return f'robot mode is {ROBOT_MODE_NAMES[self.robot_mode]}; motion needs RUNNING'
        if self.script is not None and self.program_state == PLAYING:
            return (f'robot_program_running is false (URScript program {self.script} is playing); motion needs the '
                    'External Control program playing')
        if not self.program_running:
            what = (f'program {self.loaded_program} is {self.program_state}'
                    if self.loaded_program == EXTERNAL_CONTROL_PROGRAM or self.program_state != PLAYING
                    else f'program {self.loaded_program} is playing, not {EXTERNAL_CONTROL_PROGRAM}')
            return f'robot_program_running is false ({what}); motion needs the External Control program playing'
        return None

    def unlock_wait(self) -> float:
        """[s] until unlock_protective_stop is allowed (0 when it is, or when not stopped)."""
        if self.safety_mode != PROTECTIVE_STOP or self.stop_time is None:
            return 0.0
        return max(0.0, self.stop_time + UNLOCK_DELAY - self._now)

    def program_file(self, filename: str) -> str | None:
        """The program's file name when `filename` (a name or a path in PROGRAM_DIR) exists, else None."""
        name = posixpath.basename(filename)
        path = posixpath.normpath(posixpath.join(PROGRAM_DIR, filename))
        if name in self.programs and path == posixpath.join(PROGRAM_DIR, name):
            return name
        return None

    # ---- time ------------------------------------------------------------------------------------
    def update(self, t: float) -> bool:
        """Advance to simulated time `t` [s]; True when the robot mode changed."""
        self._now = t
        changed = False
        while self._pending and t >= self._pending[0][0]:
            self.robot_mode = self._pending.pop(0)[1]
            changed = True
        return changed

    # ---- commands (dashboard) --------------------------------------------------------------------
    def power_on(self) -> str | None:
        if self.robot_mode in (POWER_ON, IDLE, RUNNING):
            return None  # the robot answers "Powering on" again and stays as it is
        self.robot_mode = POWER_ON
        self._pending = [(self._now + POWER_ON_TIME, IDLE)]
        return None

    def power_off(self) -> str | None:
        """Powers the arm off; a protective stop is cleared with the power, as a power cycle clears it on a robot."""
        if self.safety_mode == PROTECTIVE_STOP:
            self.safety_mode = NORMAL
            self.stop_cause = ''
        self.robot_mode = POWER_OFF
        self._pending = []
        self.program_state = STOPPED
        return None

    def brake_release(self) -> str | None:
        """From IDLE to RUNNING; from POWER_OFF the robot powers on first (the driver documents this)."""
        if self.robot_mode == RUNNING:
            return None
        if self.robot_mode == POWER_OFF:
            self.power_on()
        if self.robot_mode not in (POWER_ON, IDLE):
            return f'robot mode is {ROBOT_MODE_NAMES[self.robot_mode]}; brake release needs power'
        if any(mode == RUNNING for _, mode in self._pending):
            return None  # already releasing
        start = self._pending[-1][0] if self._pending else self._now
        self._pending.append((start + BRAKE_RELEASE_TIME, RUNNING))
        return None

    def play(self) -> str | None:
        if self.robot_mode != RUNNING:
            return f'robot mode is {ROBOT_MODE_NAMES[self.robot_mode]}; play needs RUNNING'
        if self.safety_mode != NORMAL:
            return f'safety mode is {SAFETY_MODE_NAMES[self.safety_mode]}; play needs NORMAL'
        self.program_state = PLAYING
        return None

    def pause(self) -> str | None:
        if self.program_state != PLAYING:
            return f'program state is {self.program_state}; pause needs PLAYING'
        self.program_state = PAUSED
        return None

    def stop(self) -> str | None:
        """Stops the program (a stopped program stays stopped)."""
        self.program_state = STOPPED
        return None

    def start_script(self, name: str) -> str | None:
        """A URScript program `name` replaces the running program (sent over the primary interface)."""
        if self.robot_mode != RUNNING:
            return f'robot mode is {ROBOT_MODE_NAMES[self.robot_mode]}; a program needs RUNNING'
        if self.safety_mode != NORMAL:
            return f'safety mode is {SAFETY_MODE_NAMES[self.safety_mode]}; a program needs NORMAL'
        self.script = name
        self.program_state = PLAYING
        return None

    def end_script(self, name: str) -> None:
        """URScript program `name` has ended: no program plays (the External Control program was replaced)."""
        if self.script == name:
            self.script = None
            self.program_state = STOPPED  # also when a protective stop paused it: ur_sim does not resume it

    def load_program(self, filename: str) -> str | None:
        """Load a program by name or path in PROGRAM_DIR; the program is STOPPED afterwards."""
        name = self.program_file(filename)
        if name is None:
            return f'program {filename!r} does not exist; programs: {", ".join(self.programs)}'
        self.program_state = STOPPED
        self.loaded_program = name
        return None

    def protective_stop(self, t: float, cause: str) -> None:
        """Enter PROTECTIVE_STOP at time `t` [s] (contact or limit, described by `cause`); the program pauses."""
        self._now = t
        if self.safety_mode == PROTECTIVE_STOP:
            return
        self.safety_mode = PROTECTIVE_STOP
        self.stop_time = t
        self.stop_cause = cause
        if self.program_state == PLAYING:
            self.program_state = PAUSED

    def unlock_protective_stop(self) -> str | None:
        if self.safety_mode != PROTECTIVE_STOP:
            return None  # nothing to unlock
        wait = self.unlock_wait()
        if wait > 0.0:
            return f'protective stop may be unlocked {UNLOCK_DELAY:.0f} s after it happened ({wait:.1f} s left)'
        self.safety_mode = NORMAL
        self.stop_cause = ''
        return None

    def restart_safety(self) -> str | None:
        """After a violation or fault: safety back to NORMAL, robot powered off (as the robot does)."""
        self.safety_mode = NORMAL
        self.stop_cause = ''
        return self.power_off()

    def resend_robot_program(self) -> str | None:
        """The driver sends its program again (headless mode): the External Control program plays."""
        if self.robot_mode != RUNNING or self.safety_mode != NORMAL:
            return self.motion_refusal()
        self.loaded_program = EXTERNAL_CONTROL_PROGRAM
        self.program_state = PLAYING
        self.script = None  # the driver's program replaces a URScript program that plays
        return None

    def hand_back_control(self) -> str | None:
        """The External Control program ends; the robot's program would continue without the driver."""
        if not self.program_running:
            return 'robot_program_running is false; there is no control to hand back'
        self.program_state = STOPPED
        return None
