"""The controller's program slot for URScript: one owner of the program that runs (sent over the primary interface or
through ``/urscript_interface``), the events a client library follows (a program started, stopped, a runtime
error, a text message), and the rule that a new program replaces the one running.

As on the robot: a ``def`` program (or bare statements) becomes the running program, so the External Control
program stops (``robot_program_running`` false) and the driver's controllers with it; a ``sec`` program runs at
once beside whatever runs and may not spend robot time. A program needs the robot RUNNING in NORMAL safety; a
dashboard stop, a protective stop or a power off ends it (ur_sim does not resume a URScript program after a
protective stop). Call everything under the simulation lock.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.motion.force_mode import ForceModeSpec
from ur_sim_driver.robot.robot_state import PLAYING, RobotState
from ur_sim_driver.robot.simulator import Simulator
from ur_sim_driver.urscript.interpreter_session import InterpreterSession
from ur_sim_driver.urscript.program import ScriptProgram

STARTED, STOPPED, RUNTIME_ERROR, TEXT = 'started', 'stopped', 'runtime_error', 'text'


@dataclass(frozen=True)
class ScriptEvent:
    """`kind`: STARTED, STOPPED, RUNTIME_ERROR or TEXT; `name`: the program's; `text`: the error or the message;
    `line`, `column`: where a runtime error points (1-based, 0: nowhere)."""

    kind: str
    name: str
    text: str = ''
    line: int = 0
    column: int = 0


class ScriptRunner:
    """Args: sim, robot: the simulated robot; factor: its speed scaling factor now; log: the robot's log;
    sockets: makes a program's client sockets (``ports.script_sockets.ScriptSockets`` on robot time), None: programs
    have no network; force_mode: starts (a ForceModeSpec) or ends (None) the robot's force mode, None: programs
    cannot use it."""

    def __init__(self, sim: Simulator, robot: RobotState, factor: Callable[[], float],
                 log: Callable[[str], None], sockets: Callable[[], object] | None = None,
                 force_mode: Callable[[ForceModeSpec | None], None] | None = None) -> None:
        self.sim, self.robot, self._factor, self._log = sim, robot, factor, log
        self._sockets = sockets
        self._force_mode = force_mode
        self.interpreter = InterpreterSession()  # the interpreter socket's queue (interpreter mode), one per robot
        self.current: ScriptProgram | None = None
        self._listeners: list[Callable[[ScriptEvent], None]] = []

    def listen(self, callback: Callable[[ScriptEvent], None]) -> Callable[[], None]:
        """Call `callback` (quickly: from the simulation loop, under the lock) with every event; returns the undo."""
        self._listeners.append(callback)
        return lambda: self._listeners.remove(callback) if callback in self._listeners else None

    def compile(self, source: str, name: str = 'unnamed') -> ScriptProgram:
        """Parse `source` into a program of this robot, ready to start; ScriptError when it does not compile. Needs
        no lock: parsing a long program must not hold up the control loop."""
        return ScriptProgram(source, self.sim, self.robot, self._factor, self._text, name,
                             self._sockets() if self._sockets is not None else None, self.interpreter,
                             self._force_mode)

    def submit(self, source: str, name: str = 'unnamed') -> ScriptProgram:
        """compile() and start() in one (under the lock)."""
        return self.start(self.compile(source, name))

    def start(self, program: ScriptProgram) -> ScriptProgram:
        """Start a compiled program (a sec program runs to its end now). ScriptError: the robot cannot run a program
        now; nothing runs then."""
        if program.secondary:
            program.run_now()
            program.close()
            if program.error is not None:
                e = program.error
                self._emit(ScriptEvent(RUNTIME_ERROR, program.name, str(e), e.line, e.column))
            return program
        refusal = self.robot.start_script(program.name)
        if refusal is not None:
            raise ScriptError(f'the robot cannot run {program.name}: {refusal}')
        if self.current is not None:
            self._finish(self.current, 'replaced by ' + program.name)
        self.current = program
        self._emit(ScriptEvent(STARTED, program.name))
        return program

    def commander(self) -> ScriptProgram | None:
        """The program that commands the arm this cycle, or None. A program the robot's state has stopped (dashboard
        stop, protective stop, power off) ends here."""
        program = self.current
        if program is None:
            return None
        if self.robot.script != program.name or self.robot.program_state != PLAYING:
            self._finish(program, f'program state {self.robot.program_state}')
            return None
        return program

    def after_cycle(self) -> None:
        """At the end of a cycle: a program that has finished (or failed) ends."""
        program = self.current
        if program is not None and program.finished:
            self._finish(program, '')

    def stop(self) -> bool:
        """Stop the running program (the client library's commandStop); False when none runs."""
        if self.current is None:
            return False
        self.robot.stop()
        self._finish(self.current, 'stopped')
        return True

    def _finish(self, program: ScriptProgram, why: str) -> None:
        program.close()
        if program is self.current:
            self.current = None
            self.robot.end_script(program.name)
        if program.error is not None:
            e = program.error
            self._emit(ScriptEvent(RUNTIME_ERROR, program.name, str(e), e.line, e.column))
        self._emit(ScriptEvent(STOPPED, program.name, why))

    def _text(self, text: str) -> None:
        self._log(text)
        self._emit(ScriptEvent(TEXT, self.current.name if self.current else '', text))

    def _emit(self, event: ScriptEvent) -> None:
        for callback in list(self._listeners):
            callback(event)
