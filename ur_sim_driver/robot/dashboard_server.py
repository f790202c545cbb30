"""The robot's dashboard server (TCP port 29999 on a real UR) as a text protocol over :class:`RobotState`, without ROS.

A real controller answers one line per command line; the driver's dashboard client sends those lines and
matches the answers. :class:`DashboardServer` answers the same commands with the same wording (UR's dashboard
server documentation for CB3 and e-series, as the Universal Robots Client Library expects it), changing the robot
state as the robot would. Commands are case-insensitive, as on the robot. A command the robot's software version
does not know yet (``software.COMMANDS``), and any unknown command, gets the server's "could not understand"
answer. In local control (an e-series in MANUAL mode) the commands that act on the robot get the robot's remote
control refusal (``robot/dashboard_roles.py``). Flight reports and support files are written into the robot's file
system, a directory given to the server. A PolyScope X robot (10.x) has no dashboard server: its Robot API
(:attr:`DashboardServer.robot_api`) answers instead. Call :meth:`DashboardServer.handle` under the simulation lock.
"""
from __future__ import annotations

import json
import posixpath
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.robot.dashboard_roles import OPERATIONAL_MODES, REMOTE_REFUSAL, USER_ROLES, OperatorControls
from ur_sim_driver.robot.robot_api import RobotApi
from ur_sim_driver.robot.robot_state import (
    PLAYING,
    PROGRAM_DIR,
    ROBOT_MODE_NAMES,
    SAFETY_MODE_NAMES,
    RobotState,
)
from ur_sim_driver.robot.software import COMMANDS, SoftwareVersion, default_version, required

INSTALLATIONS = ('default.installation',)  # installation files on the simulated robot
UNLOCK_REFUSED = ('Cannot unlock protective stop until 5s after occurrence. '
                  'Always inspect cause of protective stop before unlocking')
__all__ = ['OPERATIONAL_MODES', 'USER_ROLES', 'DashboardServer', 'Reply']
REPORT_TYPES = ('controller', 'software', 'system')  # generate flight report <type>
SERIAL_NUMBER = '20260000001'  # [digits] a UR serial number starts with its year of manufacture


@dataclass(frozen=True)
class Reply:
    """The server's answer line, and (ours, for the log) why a command was refused."""

    answer: str
    refusal: str | None = None


class DashboardServer:
    """Answers dashboard command lines from the simulated robot's state.

    Args:
        robot: the robot state the commands act on (the caller holds the simulation lock).
        ur_type: the robot's type, e.g. 'ur5e' (its model answer is 'UR5').
        version: the controller's software version; the type's default when None.
        files: the robot's file system (flight reports, support files); None: those commands fail.
    """

    def __init__(self, robot: RobotState, ur_type: str = 'ur5e', version: SoftwareVersion | None = None,
                 files: Path | None = None) -> None:
        self.robot = robot
        self.version = version or default_version(ur_type)
        self.model = load_ur_params(ur_type).model  # as the controller reports its type: a ur7e is a 'UR5'
        self.files = files
        self.installation = INSTALLATIONS[0]
        self.log: list[str] = []  # messages added with addToLog
        self.popup: str | None = None  # text of the popup shown on the (simulated) teach pendant
        self.controls = OperatorControls(self.version.e_series)  # user role, operational mode, remote control
        self.robot_api = RobotApi(robot, self.version, files) if self.version.polyscope_x else None
        self._reports = 0

    @property
    def user_role(self) -> str:
        return self.controls.user_role

    @property
    def operational_mode(self) -> str:
        return self.controls.operational_mode

    def handle(self, line: str) -> Reply:
        """Answer one command line (without the newline)."""
        text = line.strip()
        key = ' '.join(text.lower().split())
        command = key if key in _SIMPLE else next(
            (prefix for prefix, _ in _WITH_ARGUMENT if key == prefix or key.startswith(prefix + ' ')), None)
        if command is not None and not self._knows(command):
            return Reply(f"could not understand: '{text}'", f'software {self.version.dotted()} does not know it')
        refusal = None if command is None else self.controls.refusal(command)
        if refusal is not None:
            return Reply(REMOTE_REFUSAL, refusal)
        if command in _SIMPLE:
            return _SIMPLE[command](self)
        if command is not None:
            n = len(command.split())
            words = text.split(None, n)  # the argument keeps its own spacing and case
            return _ARGUMENT_METHODS[command](self, words[n] if len(words) > n else '')
        return Reply(f"could not understand: '{text}'")

    def _knows(self, command: str) -> bool:
        return command not in COMMANDS or required(command, self.version) is None

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

    def _polyscope_version(self) -> Reply:
        return Reply(f'URSoftware {self.version.dotted()} (simulated)')

    def _version_number(self) -> Reply:
        return Reply(self.version.dotted())

    def _clear_operational_mode(self) -> Reply:
        self.controls.clear_operational_mode()
        return Reply('No longer controlling the operational mode. '
                     f"Current operational mode: '{self.operational_mode}'.")

    def _set_operational_mode(self, mode: str) -> Reply:
        refusal = self.controls.set_operational_mode(mode)
        if refusal:
            return Reply(f"Failed setting operational mode: '{mode}'", refusal)
        return Reply(f"Operational mode '{mode}' is set")

    def _set_user_role(self, role: str) -> Reply:
        refusal = self.controls.set_user_role(role)
        if refusal:
            return Reply(f"Failed setting user role: '{role}'", refusal)
        return Reply(f'Setting user role: {role or "none"}')  # without a role: NONE

    def _flight_report(self, report_type: str) -> Reply:
        kind = (report_type or 'system').lower()
        if kind not in REPORT_TYPES:
            return Reply(f"Flight Report generation failed: unknown report type '{report_type}'",
                         f'report type {report_type!r} is not one of {", ".join(REPORT_TYPES)}')
        if self.files is None:
            return Reply('Flight Report generation failed', 'the robot has no file system here')
        self._reports += 1
        report_id = f'{SERIAL_NUMBER}-{self._reports:04d}'
        folder = self.files / 'flightreports'
        folder.mkdir(parents=True, exist_ok=True)
        (folder / f'{report_id}.json').write_text(json.dumps(self._report(kind, report_id), indent=2))
        return Reply(f'Flight Report generated with id: {report_id}')

    def _support_file(self, directory: str) -> Reply:
        if self.files is None:
            return Reply('Support file generation failed', 'the robot has no file system here')
        root = self.files.resolve()
        target = (root / (directory or '.').lstrip('/')).resolve()
        if root != target and root not in target.parents or not target.is_dir():
            return Reply(f"Support file generation failed: directory '{directory}' does not exist",
                         f'directory {directory!r} is not a directory of the robot ({root})')
        name = f'ur_{SERIAL_NUMBER}_{time.strftime("%Y-%m-%d_%H-%M-%S")}.zip'
        with zipfile.ZipFile(target / name, 'w', zipfile.ZIP_DEFLATED) as archive:
            archive.writestr('flight_report.json', json.dumps(self._report('system', 'support'), indent=2))
            archive.writestr('log.txt', '\n'.join(self.log))
        return Reply(f'Completed successfully: {name}')

    def _report(self, kind: str, report_id: str) -> dict:
        """What a flight report holds here: the robot's identity and state."""
        r = self.robot
        return {'id': report_id, 'type': kind, 'serial_number': SERIAL_NUMBER, 'robot_model': self.model,
                'software_version': self.version.dotted(), 'robot_mode': ROBOT_MODE_NAMES[r.robot_mode],
                'safety_mode': SAFETY_MODE_NAMES[r.safety_mode], 'program_state': r.program_state,
                'loaded_program': r.loaded_program, 'operational_mode': self.operational_mode,
                'user_role': self.user_role, 'log': list(self.log)}


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
    'is in remote control': lambda server: Reply(str(server.controls.remote_control).lower()),
    'clear operational mode': DashboardServer._clear_operational_mode,
    'get operational mode': lambda server: Reply(server.operational_mode),
    'getuserrole': lambda server: Reply(server.user_role),
    'polyscopeversion': DashboardServer._polyscope_version,
    'version': DashboardServer._version_number,
    'get serial number': _fixed(SERIAL_NUMBER),
    'get robot model': lambda server: Reply(server.model),
    'savelog': _fixed('Log saved to disk'),
    'quit': _fixed('Disconnected'),
}
# Longest prefix first: 'load installation x' must not be taken for 'load <program>'.
_WITH_ARGUMENT = (
    ('load installation', DashboardServer._load_installation),
    ('load', DashboardServer._load),
    ('popup', DashboardServer._popup),
    ('addtolog', DashboardServer._add_to_log),
    ('set operational mode', DashboardServer._set_operational_mode),
    ('setuserrole', DashboardServer._set_user_role),
    ('generate flight report', DashboardServer._flight_report),
    ('generate support file', DashboardServer._support_file),
)
_ARGUMENT_METHODS = dict(_WITH_ARGUMENT)
