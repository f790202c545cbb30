"""PolyScope X's Robot API (HTTP, ``/universal-robots/robot-api`` on a real robot) over :class:`RobotState`, without
ROS and without HTTP: one method per endpoint, each answering the status code and JSON body the robot answers.

PolyScope X (10.x) has no dashboard server on port 29999; the driver's dashboard client talks to this API instead
(Universal Robots Client Library 2.14, ``dashboard_client_implementation_x.cpp``): robot state actions
(``PUT robotstate/v1/state``), program actions (``PUT program/v1/state``: play, pause, resume, stop), queries of the
robot mode, safety mode, program state, loaded program, control mode and operational mode, and the programs stored on
the robot (``programs/v1/``: list, upload, update, download). Programs are ``.urpx`` files (JSON; the program's name
is ``program.programInformation.name``), kept in the directory ``programs`` of the robot's file system. Call the
methods under the simulation lock.
"""
from __future__ import annotations

import json
import posixpath
from dataclasses import dataclass
from pathlib import Path

from ur_sim_driver.robot.robot_state import PAUSED, ROBOT_MODE_NAMES, SAFETY_MODE_NAMES, RobotState
from ur_sim_driver.robot.software import ROBOT_API_QUERIES, SoftwareVersion

OK, BAD_REQUEST, NOT_FOUND, CONFLICT = 200, 400, 404, 409  # HTTP status codes
STATE_ACTIONS = ('POWER_ON', 'POWER_OFF', 'BRAKE_RELEASE', 'UNLOCK_PROTECTIVE_STOP', 'RESTART_SAFETY')
PROGRAM_ACTIONS = ('play', 'pause', 'resume', 'stop')
PROGRAM_SUFFIX = '.urpx'
# The Robot API's names where they differ from the primary interface's (the client library's test lists them).
_ROBOT_MODES = {**ROBOT_MODE_NAMES, **{m: 'UPDATING' for m, n in ROBOT_MODE_NAMES.items() if n == 'UPDATING_FIRMWARE'}}
_SAFETY_MODES = {m: ('EMERGENCY_STOP' if n.endswith('EMERGENCY_STOP') else n) for m, n in SAFETY_MODE_NAMES.items()}


@dataclass(frozen=True)
class ApiReply:
    """One HTTP answer: status code and body (JSON text; empty for a plain acknowledgement)."""

    status: int
    body: str = ''

    @property
    def ok(self) -> bool:
        return self.status == OK

    def json(self) -> dict:
        return json.loads(self.body) if self.body else {}


def _json(status: int, **fields) -> ApiReply:
    return ApiReply(status, json.dumps(fields))


class RobotApi:
    """The Robot API of a simulated PolyScope X controller.

    Args:
        robot: the robot state the actions change (the caller holds the simulation lock).
        version: the controller's software version (10.x).
        files: the robot's file system; programs are kept in its directory ``programs`` (None: no programs can be
            stored).
    """

    def __init__(self, robot: RobotState, version: SoftwareVersion, files: Path | None = None) -> None:
        self.robot = robot
        self.version = version
        self.programs_dir = None if files is None else files / 'programs'
        self.operational_mode = 'AUTOMATIC'  # read-only here: set on the teach pendant or by a key switch
        self.control_mode = 'REMOTE'  # the simulated robot is configured for remote control

    @property
    def queries(self) -> bool:
        """Robot API 3.1.4 (PolyScope 10.12.0 on): state queries and the program services exist."""
        return self.version[:3] >= ROBOT_API_QUERIES[:3]

    # ---- PUT robotstate/v1/state, PUT program/v1/state ---------------------------------------------------
    def state_action(self, action: str) -> ApiReply:
        """{"action": <one of STATE_ACTIONS>}. The robot acknowledges power and brake actions at once; whether the
        robot gets there shows in its robot mode afterwards. An unlock too early is refused."""
        r = self.robot
        handlers = {'POWER_ON': r.power_on, 'POWER_OFF': r.power_off, 'BRAKE_RELEASE': r.brake_release,
                    'UNLOCK_PROTECTIVE_STOP': r.unlock_protective_stop, 'RESTART_SAFETY': r.restart_safety}
        if action not in handlers:
            return _json(BAD_REQUEST, message=f"action '{action}' is not one of {', '.join(STATE_ACTIONS)}")
        refusal = handlers[action]()
        if refusal and action == 'UNLOCK_PROTECTIVE_STOP':
            return _json(CONFLICT, message=refusal)
        return ApiReply(OK)

    def program_action(self, action: str) -> ApiReply:
        """{"action": <one of PROGRAM_ACTIONS>}: refused (409) when the robot cannot do it now."""
        r = self.robot
        if action not in PROGRAM_ACTIONS:
            return _json(BAD_REQUEST, message=f"action '{action}' is not one of {', '.join(PROGRAM_ACTIONS)}")
        if action == 'resume' and r.program_state != PAUSED:
            return _json(CONFLICT, message=f'program is {r.program_state}, resume needs PAUSED')
        refusal = {'play': r.play, 'resume': r.play, 'pause': r.pause, 'stop': r.stop}[action]()
        return _json(CONFLICT, message=refusal) if refusal else ApiReply(OK)

    # ---- GET queries --------------------------------------------------------------------------------------
    def robot_mode(self) -> ApiReply:
        return _json(OK, mode=_ROBOT_MODES[self.robot.robot_mode])

    def safety_mode(self) -> ApiReply:
        return _json(OK, mode=_SAFETY_MODES[self.robot.safety_mode])

    def program_state(self) -> ApiReply:
        return _json(OK, state=self.robot.program_state)

    def loaded_program(self) -> ApiReply:
        return _json(OK, name=posixpath.splitext(self.robot.loaded_program)[0])

    def get_control_mode(self) -> ApiReply:
        return _json(OK, mode=self.control_mode)

    def get_operational_mode(self) -> ApiReply:
        return _json(OK, mode=self.operational_mode)

    # ---- programs -----------------------------------------------------------------------------------------
    def load(self, name: str) -> ApiReply:
        """PUT program/v1/loaded {"name": <program name, without extension>}."""
        stored = [p for p in self.robot.programs if posixpath.splitext(p)[0] == name]
        if not name or not stored:
            return _json(NOT_FOUND, message=f"program '{name}' does not exist; programs: "
                                             f"{', '.join(posixpath.splitext(p)[0] for p in self.robot.programs)}")
        refusal = self.robot.load_program(stored[0])
        return _json(CONFLICT, message=refusal) if refusal else ApiReply(OK)

    def programs(self) -> ApiReply:
        """GET programs/v1/: every stored program's information."""
        infos = [info for _, info in self._stored()]
        return ApiReply(OK, json.dumps({'programs': infos}))

    def upload(self, content: str, update: bool = False) -> ApiReply:
        """POST (new) or PUT (update) programs/v1/ with a .urpx file's content: {"programName": <name>}."""
        if self.programs_dir is None:
            return _json(CONFLICT, message='the robot has no file system here')
        try:
            info = json.loads(content)['program']['programInformation']
            name = info['name']
        except (ValueError, KeyError, TypeError) as exc:
            return _json(BAD_REQUEST, message=f'not a PolyScope X program (.urpx): {exc}')
        if not isinstance(name, str) or not name or '/' in name or name.startswith('.'):
            return _json(BAD_REQUEST, message=f'program name {name!r} is not a valid file name')
        path = self.programs_dir / (name + PROGRAM_SUFFIX)
        if path.exists() != update:
            return (_json(BAD_REQUEST, message=f"program '{name}' exists already") if not update
                    else _json(NOT_FOUND, message=f"program '{name}' does not exist"))
        self.programs_dir.mkdir(parents=True, exist_ok=True)
        path.write_text(content)
        self.robot.programs = tuple(dict.fromkeys((*self.robot.programs, path.name)))
        return _json(OK, programName=name)

    def download(self, name: str) -> ApiReply:
        """GET programs/v1/<name>: the program's .urpx content."""
        path = None if self.programs_dir is None else self.programs_dir / (name + PROGRAM_SUFFIX)
        if path is None or '/' in name or not path.is_file():
            return _json(NOT_FOUND, message=f"program '{name}' does not exist")
        return ApiReply(OK, path.read_text())

    def _stored(self) -> list[tuple[Path, dict]]:
        if self.programs_dir is None or not self.programs_dir.is_dir():
            return []
        stored = []
        for path in sorted(self.programs_dir.glob('*' + PROGRAM_SUFFIX)):
            info = json.loads(path.read_text())['program']['programInformation']
            stored.append((path, {key: info.get(key) for key in ('name', 'description', 'createdDate',
                                                                  'lastSavedDate', 'lastModifiedDate',
                                                                  'programState')}))
        return stored
