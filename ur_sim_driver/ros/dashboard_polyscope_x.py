"""The driver's `dashboard_client` services on a PolyScope X robot (10.x), over the robot's Robot API.

On PolyScope X the driver (ur_robot_driver at a16a268, ``dashboard_client_ros.cpp``) uses the client library's
POLYSCOPE_X policy (Universal Robots Client Library 2.14, ``DashboardClientImplX``): HTTP calls to the Robot API
instead of dashboard command lines, and the `~/resume` service, which only this policy has. What that client does,
ur_sim does against :class:`~ur_sim_driver.robot.robot_api.RobotApi`:

- Trigger services answer the body of the robot's answer followed by ``, status_code: <code>``, success when the code
  is 200; they do not wait for the robot to reach the state (the client library does not). Commands the Robot API
  lacks answer the client library's "<command> is not implemented for DashboardClientImplX." (close popups, shutdown,
  clear operational mode); `quit` has nothing to close.
- The other services answer "Not implemented for this robot software version." for what the Robot API lacks (popup,
  log, program saved / running, installation, PolyScope version, serial number, robot model, safety status, user
  role, setting the operational mode, flight report, support file), as the driver does; the queries and program
  services need Robot API 3.1.4 (PolyScope 10.12.0) and answer the same before it. `raw_request` answers the client
  library's "sendAndReceive is not implemented" text: there is no dashboard server to send lines to.
"""
from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rclpy.node import Node
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import ProgramInformation
from ur_dashboard_msgs.srv import (
    AddToLog,
    DownloadProgram,
    GenerateFlightReport,
    GenerateSupportFile,
    GetLoadedProgram,
    GetOperationalMode,
    GetPolyScopeVersion,
    GetPrograms,
    GetProgramState,
    GetRobotMode,
    GetRobotModel,
    GetSafetyMode,
    GetSafetyStatus,
    GetSerialNumber,
    GetUserRole,
    IsInRemoteControl,
    IsProgramRunning,
    IsProgramSaved,
    Load,
    Popup,
    RawRequest,
    SetOperationalMode,
    SetUserRole,
    UploadProgram,
)

from ur_sim_driver.robot.robot_api import ApiReply, RobotApi
from ur_sim_driver.robot.software import DASHBOARD_X
from ur_sim_driver.ros.dashboard_commands import (
    NOT_CONNECTED,
    NOT_IMPLEMENTED,
    ROBOT_MODES_BY_NAME,
    SAFETY_MODES_BY_NAME,
    NotConnected,
)

QUIT_ANSWER = 'Nothing to quit here. All is fine.'
TOO_OLD = ('{} is not implemented for Robot API version < 3.1.4. Please upgrade the robot to PolyScope 10.12.0 or '
           'higher to use this command.')
UINT_MAX = 2 ** 32  # the client library keeps program dates in an unsigned int


def not_implemented_x(command: str) -> str:
    """The client library's exception text for a command DashboardClientImplX does not have."""
    return f'{command} is not implemented for DashboardClientImplX.'


def configure_polyscope_x(client, node: Node) -> None:
    """The services of `client` (the ros/dashboard.py DashboardClient) on a PolyScope X robot: none before 10.11.0
    (the driver's dashboard client exits there), else `~/connect` and :class:`PolyScopeXServices`'."""
    version = client.server.version
    if version[:3] < DASHBOARD_X[:3]:
        node.get_logger().fatal(f'The dashboard server for PolyScope X is only available from version 10.11.0 and '
                                f'later. The connected robot has version {version}. Exiting now.')
        return

    def call(request: Callable[[], ApiReply]) -> ApiReply:
        with client._connection:
            if not client.connected:
                raise NotConnected(NOT_CONNECTED)
        with client.host.lock:
            return request()

    def connect(request, response: Trigger.Response) -> Trigger.Response:
        client.connected = response.success = True  # the Robot API keeps no connection: connecting succeeds
        return response
    node.create_service(Trigger, '~/connect', connect)
    PolyScopeXServices(client.server.robot_api, call).create(node)


class PolyScopeXServices:
    """`/dashboard_client/*` of the driver's POLYSCOPE_X policy.

    Args:
        api: the robot's Robot API.
        call: runs a function of the API under the simulation lock and returns its result; raises
            :class:`~ur_sim_driver.ros.dashboard_commands.NotConnected` while the client is not connected.
    """

    def __init__(self, api: RobotApi, call: Callable) -> None:
        self.api, self.call = api, call

    def create(self, node: Node) -> None:
        """Every service of the driver's dashboard client on `node` (`~/connect` is the caller's)."""
        api = self.api
        triggers = {
            'power_on': lambda: api.state_action('POWER_ON'), 'power_off': lambda: api.state_action('POWER_OFF'),
            'brake_release': lambda: api.state_action('BRAKE_RELEASE'),
            'unlock_protective_stop': lambda: api.state_action('UNLOCK_PROTECTIVE_STOP'),
            'restart_safety': lambda: api.state_action('RESTART_SAFETY'),
            'play': lambda: api.program_action('play'), 'pause': lambda: api.program_action('pause'),
            'resume': lambda: api.program_action('resume'), 'stop': lambda: api.program_action('stop')}
        for name, action in triggers.items():
            node.create_service(Trigger, f'~/{name}', self._trigger(action))
        for name, command in (('close_popup', 'commandClosePopup'), ('close_safety_popup', 'commandCloseSafetyPopup'),
                              ('shutdown', 'commandShutdown'),
                              ('clear_operational_mode', 'commandClearOperationalMode')):
            node.create_service(Trigger, f'~/{name}', self._refused_trigger(not_implemented_x(command)))
        node.create_service(Trigger, '~/quit', self._refused_trigger(QUIT_ANSWER, success=True))
        for srv_type, name in (
                (IsProgramRunning, 'program_running'), (IsProgramSaved, 'program_saved'), (Popup, 'popup'),
                (AddToLog, 'add_to_log'), (Load, 'load_installation'), (GetSerialNumber, 'get_serial_number'),
                (GetPolyScopeVersion, 'get_polyscope_version'), (GetRobotModel, 'get_robot_model'),
                (GetSafetyStatus, 'get_safety_status'), (GetUserRole, 'get_user_role'),
                (SetUserRole, 'set_user_role'), (SetOperationalMode, 'set_operational_mode'),
                (GenerateFlightReport, 'generate_flight_report'), (GenerateSupportFile, 'generate_support_file')):
            node.create_service(srv_type, f'~/{name}', self._not_implemented)
        node.create_service(RawRequest, '~/raw_request', self._on_raw_request)
        node.create_service(GetRobotMode, '~/get_robot_mode', self._query(api.robot_mode, self._robot_mode))
        node.create_service(GetSafetyMode, '~/get_safety_mode', self._query(api.safety_mode, self._safety_mode))
        node.create_service(GetLoadedProgram, '~/get_loaded_program', self._query(api.loaded_program, self._loaded))
        node.create_service(GetOperationalMode, '~/get_operational_mode',
                            self._query(api.get_operational_mode, self._operational_mode))
        node.create_service(GetProgramState, '~/program_state',
                            self._query(api.program_state, self._program_state, always=True))
        node.create_service(GetPrograms, '~/get_programs', self._query(api.programs, self._programs))
        node.create_service(Load, '~/load_program', self._on_load_program)
        node.create_service(IsInRemoteControl, '~/is_in_remote_control', self._on_remote_control)
        node.create_service(UploadProgram, '~/upload_program', self._upload(update=False))
        node.create_service(UploadProgram, '~/update_program', self._upload(update=True))
        node.create_service(DownloadProgram, '~/download_program', self._on_download)

    # ---- the driver's wrappers -----------------------------------------------------------------------------
    def _send(self, request: Callable[[], ApiReply], response) -> ApiReply | None:
        """One API call; its answer, or None with `answer`/`success` filled when the client is not connected."""
        try:
            return self.call(request)
        except NotConnected as exc:
            response.answer, response.success = str(exc), False
            return None

    def _trigger(self, action: Callable[[], ApiReply]):
        def callback(request, response: Trigger.Response) -> Trigger.Response:
            try:
                reply = self.call(action)
            except NotConnected as exc:
                response.message, response.success = str(exc), False
                return response
            response.message, response.success = f'{reply.body}, status_code: {reply.status}', reply.ok
            return response
        return callback

    @staticmethod
    def _refused_trigger(message: str, success: bool = False):
        def callback(request, response: Trigger.Response) -> Trigger.Response:
            response.message, response.success = message, success
            return response
        return callback

    @staticmethod
    def _not_implemented(request, response):
        response.answer, response.success = NOT_IMPLEMENTED, False
        return response

    def _query(self, request: Callable[[], ApiReply], fill, always: bool = False):
        """A GET service: `answer` is the body, `fill(response, data)` on success; before Robot API 3.1.4 not
        implemented (unless `always`)."""
        def callback(_, response):
            if not always and not self.api.queries:
                return self._not_implemented(_, response)
            reply = self._send(request, response)
            if reply is not None:
                response.answer, response.success = reply.body, reply.ok
                if reply.ok:
                    fill(response, reply.json())
            return response
        return callback

    # ---- fillers -------------------------------------------------------------------------------------------
    @staticmethod
    def _robot_mode(response, data: dict) -> None:
        if data['mode'] in ROBOT_MODES_BY_NAME:  # the driver leaves the mode at 0 for a name it does not know
            response.robot_mode.mode = ROBOT_MODES_BY_NAME[data['mode']]

    @staticmethod
    def _safety_mode(response, data: dict) -> None:
        if data['mode'] in SAFETY_MODES_BY_NAME:
            response.safety_mode.mode = SAFETY_MODES_BY_NAME[data['mode']]

    @staticmethod
    def _loaded(response, data: dict) -> None:
        response.program_name = data['name']

    @staticmethod
    def _operational_mode(response, data: dict) -> None:
        response.operational_mode.mode = data['mode']

    @staticmethod
    def _program_state(response, data: dict) -> None:
        response.state.state = data['state']  # PolyScope X does not report the program's name

    @staticmethod
    def _programs(response, data: dict) -> None:
        for p in data['programs']:
            response.programs.append(ProgramInformation(
                name=p['name'], description=p['description'] or '',
                created_date=(p['createdDate'] or 0) % UINT_MAX, last_saved_date=(p['lastSavedDate'] or 0) % UINT_MAX,
                last_modified_date=(p['lastModifiedDate'] or 0) % UINT_MAX, program_state=p['programState'] or ''))

    # ---- services with their own handling --------------------------------------------------------------------
    def _on_raw_request(self, request, response: RawRequest.Response) -> RawRequest.Response:
        response.answer = 'sendAndReceive is not implemented for DashboardClientImplX.'
        return response

    def _on_load_program(self, request: Load.Request, response: Load.Response) -> Load.Response:
        reply = self._send(lambda: self.api.load(request.filename), response)
        if reply is not None:
            response.answer, response.success = f'{reply.body}, status_code: {reply.status}', reply.ok
        return response

    def _on_remote_control(self, request, response: IsInRemoteControl.Response) -> IsInRemoteControl.Response:
        if not self.api.queries:
            response.answer, response.success = TOO_OLD.format('commandIsInRemoteControl'), False
            return response
        reply = self._send(self.api.get_control_mode, response)
        if reply is not None:
            response.remote_control = reply.ok and reply.json()['mode'] == 'REMOTE'
            response.success = True
        return response

    def _upload(self, update: bool):
        def callback(request: UploadProgram.Request, response: UploadProgram.Response) -> UploadProgram.Response:
            if not self.api.queries:
                return self._not_implemented(request, response)
            try:  # the client reads the file on the driver's side, line by line
                content = ''.join(line.rstrip('\n') + '\n' for line in Path(request.file_path).open())
            except OSError:
                response.answer, response.success = f'URPX File not found: {request.file_path}', False
                return response
            reply = self._send(lambda: self.api.upload(content, update), response)
            if reply is not None:
                response.answer, response.success = reply.body, reply.ok
                if reply.ok:
                    response.program_name = reply.json()['programName']
            return response
        return callback

    def _on_download(self, request: DownloadProgram.Request,
                     response: DownloadProgram.Response) -> DownloadProgram.Response:
        if not self.api.queries:
            return self._not_implemented(request, response)
        name, path = request.program_name, request.target_path
        if not name or not path:
            response.answer = ('Both program_name and save_path parameters should be populated.'
                               + (' Program name is empty.' if not name else '') + (' Save path is empty.' if not path
                                                                                    else ''))
            response.success = False
            return response
        reply = self._send(lambda: self.api.download(name), response)
        if reply is None:
            return response
        if not reply.ok:
            response.answer, response.success = reply.body, False
            return response
        try:
            Path(path).write_text(reply.body)
        except OSError:
            response.answer, response.success = f'Failed to open file for saving: {path}', False
            return response
        response.answer, response.success = f'Downloaded program to {path}', True
        return response

