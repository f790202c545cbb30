"""The robot's dashboard server (TCP port 29999 on a real UR) as a text protocol over :class:`RobotState`, without ROS.

A real controller answers one line per command line; the driver's dashboard client sends those lines and
matches the answers. :class:`DashboardServer` answers the same commands with the same wording (UR's dashboard
server documentation for e-series / PolyScope 5, as the Universal Robots Client Library expects it), changing
the robot state as the robot would. Commands are case-insensitive, as on the robot. Unknown commands get the
server's "could not understand" answer. Call :meth:`DashboardServer.handle` under the simulation lock.
"""
from __future__ import annotations

import posixpath
from dataclasses import dataclass

from ur_sim_driver.robot.robot_state import (
    PLAYING,
    PROGRAM_DIR,
    ROBOT_MODE_NAMES,
    SAFETY_MODE_NAMES,
    RobotState,
)

INSTALLATIONS = ('default.installation',)  # installation files on the simulated robot
UNLOCK_REFUSED = ('Cannot unlock protective stop until 5s after occurrence. '
                  'Always inspect cause of protective stop before unlocking')
OPERATIONAL_MODE = 'AUTOMATIC'  # what the simulated robot reports after 'clear operational mode'


@dataclass(frozen=True)
class Reply:
    """The server's answer line, and (ours, for the log) why a command was refused."""

    answer: str
    refusal: str | None = None


class DashboardServer:
    """Answers dashboard command lines from the simulated robot's state.

    Args:
        robot: the robot state the commands act on (the caller holds the simulation lock).
    """

    def __init__(self, robot: RobotState) -> None:
        self.robot = robot
        self.installation = INSTALLATIONS[0]
        self.log: list[str] = []  # messages added with addToLog
        self.popup: str | None = None  # text of the popup shown on the (simulated) teach pendant

    def handle(self, line: str) -> Reply:
        """Answer one command line (without the newline)."""
        text = line.strip()
        key = ' '.join(text.lower().split())
        simple = _SIMPLE.get(key)
        if simple is not None:
            return simple(self)
        for prefix, method in _WITH_ARGUMENT:
            if key == prefix or key.startswith(prefix + ' '):
                n = len(prefix.split())
                words = text.split(None, n)  # the argument keeps its own spacing and case
                return method(self, words[n] if len(words) > n else '')
        return Reply(f"could not understand: '{text}'")

    # ---- commands ------------------------------------------------------------------------------
    def _power_on(self) -> Reply:
        return Reply('Powering on', self.robot.power_on())

    def _power_off(self) -> Reply:
        return Reply('Powering off', self.robot.power_off())

    def _brake_release(self) -> Reply:
        # The robot acknowledges at once; whether the brakes come off shows in the robot mode afterwards.
        return Reply('Brake releasing', self.robot.brake_release())

    def _play(self) -> Reply:
        refusal = self.robot.play()
        return Reply('Failed to execute: play' if refusal else 'Starting program', refusal)

    def _pause(self) -> Reply:
        refusal = self.robot.pause()
        return Reply('Failed to execute: pause' if refusal else 'Pausing program', refusal)

    def _stop(self) -> Reply:
        refusal = self.robot.stop()
        return Reply('Failed to execute: stop' if refusal else 'Stopped', refusal)

    def _unlock(self) -> Reply:
        refusal = self.robot.unlock_protective_stop()
        return Reply(UNLOCK_REFUSED if refusal else 'Protective stop releasing', refusal)

    def _restart_safety(self) -> Reply:
        return Reply('Restarting safety', self.robot.restart_safety())

    def _shutdown(self) -> Reply:
        # The controller goes down; here the arm powers off and the dashboard client is disconnected.
        return Reply('Shutting down', self.robot.power_off())

    def _close_popup(self) -> Reply:
        self.popup = None
        return Reply('closing popup')

    def _robot_mode(self) -> Reply:
        return Reply(f'Robotmode: {ROBOT_MODE_NAMES[self.robot.robot_mode]}')

    def _safety_mode(self) -> Reply:
        return Reply(f'Safetymode: {SAFETY_MODE_NAMES[self.robot.safety_mode]}')

    def _safety_status(self) -> Reply:
        return Reply(f'Safetystatus: {SAFETY_MODE_NAMES[self.robot.safety_mode]}')

    def _running(self) -> Reply:
        # Any program playing counts here (robot_program_running is about External Control only).
        return Reply(f'Program running: {str(self.robot.program_state == PLAYING).lower()}')

    def _program_state(self) -> Reply:
        return Reply(f'{self.robot.program_state} {self.robot.loaded_program}')

    def _loaded_program(self) -> Reply:
        return Reply(f'Loaded program: {self.robot.loaded_program_path}')

    def _program_saved(self) -> Reply:
        return Reply(f'true {self.robot.loaded_program}')

    def _load(self, filename: str) -> Reply:
        refusal = self.robot.load_program(filename)
        if refusal:
            return Reply(f'File not found: {filename}', refusal)
        return Reply(f'Loading program: {self.robot.loaded_program_path}')

    def _load_installation(self, filename: str) -> Reply:
        name = posixpath.basename(filename)
        if name not in INSTALLATIONS or posixpath.normpath(posixpath.join(PROGRAM_DIR, filename)) != \
                posixpath.join(PROGRAM_DIR, name):
            return Reply(f'File not found: {filename}', f'installation {filename!r} does not exist; '
                                                         f'installations: {", ".join(INSTALLATIONS)}')
        self.installation = name
        return Reply(f'Loading installation: {posixpath.join(PROGRAM_DIR, name)}')

    def _popup(self, text: str) -> Reply:
        self.popup = text
        return Reply('showing popup')

    def _add_to_log(self, text: str) -> Reply:
        if not text:
            return Reply('No log message to add')
        self.log.append(text)
        return Reply('Added log message')


def _fixed(answer: str):
    return lambda server: Reply(answer)


_SIMPLE = {
    'power on': DashboardServer._power_on,
    'power off': DashboardServer._power_off,
    'brake release': DashboardServer._brake_release,
    'play': DashboardServer._play,
    'pause': DashboardServer._pause,
    'stop': DashboardServer._stop,
    'unlock protective stop': DashboardServer._unlock,
    'restart safety': DashboardServer._restart_safety,
    'shutdown': DashboardServer._shutdown,
    'close popup': DashboardServer._close_popup,
    'close safety popup': _fixed('closing safety popup'),
    'robotmode': DashboardServer._robot_mode,
    'safetymode': DashboardServer._safety_mode,
    'safetystatus': DashboardServer._safety_status,
    'running': DashboardServer._running,
    'programstate': DashboardServer._program_state,
    'get loaded program': DashboardServer._loaded_program,
    'isprogramsaved': DashboardServer._program_saved,
    'is in remote control': _fixed('true'),  # dashboard commands are accepted: the robot is in remote control
    'clear operational mode': _fixed('No longer controlling the operational mode. '
                                     f"Current operational mode: '{OPERATIONAL_MODE}'."),
    'quit': _fixed('Disconnected'),
}
# Longest prefix first: 'load installation x' must not be taken for 'load <program>'.
_WITH_ARGUMENT = (
    ('load installation', DashboardServer._load_installation),
    ('load', DashboardServer._load),
    ('popup', DashboardServer._popup),
    ('addtolog', DashboardServer._add_to_log),
)
