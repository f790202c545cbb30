"""The driver's `dashboard_client` node: `/dashboard_client/*` services in front of the robot's dashboard server.

In the real driver (ur_robot_driver 3.8, ``dashboard_client_ros.cpp`` over the Universal Robots Client
Library) each service sends one command line to the robot's dashboard server and checks the answer; commands
that change the robot also wait until the robot reports the new state (power on: robot mode IDLE or RUNNING;
brake release and unlock: RUNNING; play / pause / stop: the program state; load: STOPPED <program>). A
service therefore returns once the robot is there, so `power_on`, `brake_release`, `play` can be called one
after the other. `message` / `answer` is the server's answer; when the answer is not the expected one it is
the client library's "Expected: <pattern>, but received: <answer>". ur_sim does the same against
:class:`~ur_sim_driver.robot.dashboard_server.DashboardServer`, waiting in simulated time.

Before sending, the client library checks that the robot's software version knows the command
(``robot/software.py``) and answers with its version-mismatch text if not; the program services of PolyScope X
(get_programs, upload_program, update_program, download_program) answer "Not implemented for this robot software
version." on CB3 and PolyScope 5, as the driver's do. On PolyScope X (10.x) the services are the driver's
POLYSCOPE_X ones over the robot's Robot API (``ros/dashboard_polyscope_x.py``).
"""
from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable

from rclpy.node import Node
from std_srvs.srv import Trigger
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

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.robot.dashboard_server import DashboardServer
from ur_sim_driver.robot.robot_state import STOPPED, RobotState
from ur_sim_driver.robot.software import COMMANDS, required
from ur_sim_driver.ros.dashboard_commands import (
    NOT_CONNECTED,
    NOT_IMPLEMENTED,
    ROBOT_MODES_BY_NAME,
    SAFETY_MODES_BY_NAME,
    SAFETY_STATUS_BY_NAME,
    STALL_TIMEOUT,
    TRIGGERS,
    Command,
    NotConnected,
)
from ur_sim_driver.ros.dashboard_polyscope_x import configure_polyscope_x

__all__ = ['NOT_CONNECTED', 'NOT_IMPLEMENTED', 'DashboardClient']


class DashboardClient(Component):
    """`/dashboard_client/*`: the driver's dashboard services over the simulated robot."""

    name = 'dashboard_client'
    type_name = 'ur_robot_driver/dashboard_client'  # a node of the driver, not a controller
    is_controller = False

    def __init__(self) -> None:
        super().__init__()
        self.server: DashboardServer | None = None
        self.connected = True  # the driver connects at start-up
        self._connection = threading.Lock()

    def on_configure(self, host: Host, node: Node) -> None:
        self.server = host.dashboard  # the robot's own: the TCP port (ports/dashboard_port.py) answers from it too
        # The driver's dashboard client node parameter (set as `-p dashboard_client:autoconnect:=false`): without
        # it the client starts disconnected and waits for ~/connect.
        self.connected = bool(node.declare_parameter('autoconnect', True).value)
        if not self.connected:
            node.get_logger().info('Dashboard client started with autoconnect disabled. Call the ~/connect service '
                                   'to connect to the simulated robot.')
        if self.server.version.polyscope_x:  # the Robot API instead of a dashboard server
            configure_polyscope_x(self, node)
            return
        for name, command in TRIGGERS.items():
            node.create_service(Trigger, f'~/{name}', self._trigger_callback(command))
        node.create_service(Trigger, '~/connect', self._on_connect)
        node.create_service(GetRobotMode, '~/get_robot_mode', self._on_robot_mode)
        node.create_service(GetSafetyMode, '~/get_safety_mode', self._on_safety_mode)
        node.create_service(IsProgramRunning, '~/program_running', self._on_running)
        node.create_service(GetProgramState, '~/program_state', self._on_program_state)
        node.create_service(IsProgramSaved, '~/program_saved', self._on_program_saved)
        node.create_service(GetLoadedProgram, '~/get_loaded_program', self._on_loaded_program)
        node.create_service(Load, '~/load_program', self._on_load_program)
        node.create_service(Load, '~/load_installation', self._on_load_installation)
        node.create_service(IsInRemoteControl, '~/is_in_remote_control', self._on_remote_control)
        node.create_service(Popup, '~/popup', self._on_popup)
        node.create_service(AddToLog, '~/add_to_log', self._on_add_to_log)
        node.create_service(RawRequest, '~/raw_request', self._on_raw_request)
        node.create_service(GetSerialNumber, '~/get_serial_number', self._on_serial_number)
        node.create_service(GetPolyScopeVersion, '~/get_polyscope_version', self._on_polyscope_version)
        node.create_service(GetRobotModel, '~/get_robot_model', self._on_robot_model)
        node.create_service(GetSafetyStatus, '~/get_safety_status', self._on_safety_status)
        node.create_service(GetUserRole, '~/get_user_role', self._on_get_user_role)
        node.create_service(SetUserRole, '~/set_user_role', self._on_set_user_role)
        node.create_service(GetOperationalMode, '~/get_operational_mode', self._on_get_operational_mode)
        node.create_service(SetOperationalMode, '~/set_operational_mode', self._on_set_operational_mode)
        node.create_service(GenerateFlightReport, '~/generate_flight_report', self._on_flight_report)
        node.create_service(GenerateSupportFile, '~/generate_support_file', self._on_support_file)
        # PolyScope X's program services: not implemented on CB3 and PolyScope 5 (the driver's answer).
        for srv_type, name in ((GetPrograms, 'get_programs'), (UploadProgram, 'upload_program'),
                               (UploadProgram, 'update_program'), (DownloadProgram, 'download_program')):
            node.create_service(srv_type, f'~/{name}', self._not_implemented)

    # ---- talking to the server -------------------------------------------------------------------
    def send(self, line: str) -> str:
        """One command line to the server (under the simulation lock); its answer.

        Raises:
            NotConnected: after `quit` or `shutdown`, until `connect`.
        """
        with self._connection:
            if not self.connected:
                raise NotConnected(NOT_CONNECTED)
            with self.host.lock:
                reply = self.server.handle(line)
            if ' '.join(line.lower().split()) in ('quit', 'shutdown'):
                self.connected = False
        if reply.refusal:
            self.node.get_logger().info(f"dashboard '{line}': {reply.answer} ({reply.refusal})")
        return reply.answer

    def mismatch(self, line: str) -> str | None:
        """The client library's refusal of `line` when the robot's software version does not know its command (it
        is never sent then), else None."""
        words = line.split()
        for n in range(min(len(words), 4), 0, -1):  # the longest command the line starts with
            key = ' '.join(words[:n]).lower()
            if key in COMMANDS:
                version = self.server.version
                needed = required(key, version)
                if needed is None:
                    return None
                return (f"Dashboard command '{' '.join(words[:n])}' is not supported by this robot version."
                        f'(Required version: {needed}, actual version: {version})')
        return None

    def run(self, command: Command) -> tuple[bool, str]:
        """Send `command`, check its answer and wait for its state: (success, message)."""
        refused = self.mismatch(command.line)
        if refused is not None:
            return False, refused
        try:
            answer = self.send(command.line)
        except NotConnected as exc:
            return False, str(exc)
        if not re.fullmatch(command.expected, answer):
            return False, f'Expected: {command.expected}, but received: {answer}'
        if command.until is not None and not self._wait(command.until, command.timeout):
            return not command.strict, command.failed if command.strict else answer
        return True, answer

    def _wait(self, condition: Callable[[RobotState], bool], timeout: float) -> bool:
        """Wait until `condition` holds or `timeout` [s] of simulated time passed, as the simulation loop sees it at
        the end of a cycle; False also when simulated time stops advancing for STALL_TIMEOUT of wall time."""
        host = self.host
        sim = host.sim
        t_end = sim.time + timeout
        event = host.when(lambda: condition(host.robot) or sim.time >= t_end)
        last_t, last_wall = sim.time, time.monotonic()
        try:
            while not event.wait(0.01):
                t = sim.time
                if t != last_t:
                    last_t, last_wall = t, time.monotonic()
                elif time.monotonic() - last_wall > STALL_TIMEOUT:
                    return False  # the simulation is not running: nothing will change
        finally:
            host.forget(event)
        with host.lock:
            return condition(host.robot)

    def _query(self, line: str, pattern: str, response) -> re.Match | None:
        """Send a query; fill `answer` and `success` as the driver does; the match when successful."""
        refused = self.mismatch(line)
        if refused is not None:
            response.answer, response.success = refused, False
            return None
        try:
            response.answer = self.send(line)
        except NotConnected as exc:
            response.answer, response.success = str(exc), False
            return None
        match = re.fullmatch(pattern, response.answer)
        response.success = match is not None
        if match is None:
            response.answer = f'Expected: {pattern}, but received: {response.answer}'
        return match

    # ---- service callbacks -------------------------------------------------------------------------
    def _trigger_callback(self, command: Command):
        def callback(request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
            response.success, response.message = self.run(command)
            return response
        return callback

    def _on_connect(self, request, response: Trigger.Response) -> Trigger.Response:
        with self._connection:
            # The client library refuses to connect a socket that is connected already.
            response.success = not self.connected
            self.connected = True
        return response

    def _on_robot_mode(self, request, response: GetRobotMode.Response) -> GetRobotMode.Response:
        match = self._query('robotmode', r'Robotmode: (.*)', response)
        if match:
            response.robot_mode.mode = ROBOT_MODES_BY_NAME[match[1]]
        return response

    def _on_safety_mode(self, request, response: GetSafetyMode.Response) -> GetSafetyMode.Response:
        match = self._query('safetymode', r'Safetymode: (.*)', response)
        if match:
            response.safety_mode.mode = SAFETY_MODES_BY_NAME[match[1]]
        return response

    def _on_running(self, request, response: IsProgramRunning.Response) -> IsProgramRunning.Response:
        match = self._query('running', r'Program running: (true|false)', response)
        if match:
            response.program_running = match[1] == 'true'
        return response

    def _on_program_state(self, request, response: GetProgramState.Response) -> GetProgramState.Response:
        match = self._query('programState', r'(STOPPED|PLAYING|PAUSED) (.*)', response)
        if match:
            response.state.state, response.program_name = match[1], match[2]
        return response

    def _on_program_saved(self, request, response: IsProgramSaved.Response) -> IsProgramSaved.Response:
        match = self._query('isProgramSaved', r'(true|false) (.*\.urp)', response)
        if match:
            response.program_saved, response.program_name = match[1] == 'true', match[2]
        return response

    def _on_loaded_program(self, request, response: GetLoadedProgram.Response) -> GetLoadedProgram.Response:
        match = self._query('get loaded program', r'Loaded program: (.*)', response)
        if match:
            response.program_name = match[1]
        return response

    def _on_load_program(self, request: Load.Request, response: Load.Response) -> Load.Response:
        filename = request.filename
        name = filename.rsplit('/', 1)[-1]
        response.success, response.answer = self.run(Command(
            f'load {filename}', f'Loading program: .*{re.escape(filename)}.*',
            lambda r: r.program_state == STOPPED and r.loaded_program == name,
            f"Failed to load program. Expected 'programState' to be 'STOPPED {name}', but did not receive it."))
        return response

    def _on_load_installation(self, request: Load.Request, response: Load.Response) -> Load.Response:
        response.success, response.answer = self.run(Command(
            f'load installation {request.filename}', f'Loading installation: .*{re.escape(request.filename)}.*'))
        return response

    def _on_remote_control(self, request, response: IsInRemoteControl.Response) -> IsInRemoteControl.Response:
        # The driver fills only remote_control and success here; `answer` stays empty unless the call fails.
        refused = self.mismatch('is in remote control')
        if refused is not None:
            response.answer, response.success = refused, False
            return response
        try:
            response.remote_control = self.send('is in remote control') == 'true'
            response.success = True
        except NotConnected as exc:
            response.answer, response.success = str(exc), False
        return response

    def _on_popup(self, request: Popup.Request, response: Popup.Response) -> Popup.Response:
        response.success, response.answer = self.run(Command(f'popup {request.message}', 'showing popup'))
        return response

    def _on_add_to_log(self, request: AddToLog.Request, response: AddToLog.Response) -> AddToLog.Response:
        response.success, response.answer = self.run(Command(f'addToLog {request.message}', 'Added log message'))
        return response

    def _on_raw_request(self, request: RawRequest.Request, response: RawRequest.Response) -> RawRequest.Response:
        try:
            response.answer = self.send(request.query)
        except NotConnected as exc:
            response.answer = str(exc)
        return response

    def _on_serial_number(self, request, response: GetSerialNumber.Response) -> GetSerialNumber.Response:
        if self._query('get serial number', r'(?:20).*', response):
            response.serial_number = int(response.answer)
        return response

    def _on_polyscope_version(self, request, response: GetPolyScopeVersion.Response) -> GetPolyScopeVersion.Response:
        if self._query('PolyscopeVersion', r'(?:URSoftware ).*', response):
            numbers = re.search(r'([0-9]+)\.([0-9]+)\.([0-9]+)\.([0-9]+)', response.answer)
            if numbers:
                v = response.version
                v.major, v.minor, v.bugfix, v.build = (int(x) for x in numbers.groups())
        return response

    def _on_robot_model(self, request, response: GetRobotModel.Response) -> GetRobotModel.Response:
        if self._query('get robot model', r'(?:UR).*', response):
            response.robot_model = response.answer
        return response

    def _on_safety_status(self, request, response: GetSafetyStatus.Response) -> GetSafetyStatus.Response:
        match = self._query('safetystatus', r'Safetystatus: (.*)', response)
        if match:
            response.safety_status.status = SAFETY_STATUS_BY_NAME.get(match[1], 0)
        return response

    def _on_get_user_role(self, request, response: GetUserRole.Response) -> GetUserRole.Response:
        if self._query('getUserRole', r'(PROGRAMMER|OPERATOR|NONE|LOCKED|RESTRICTED)', response):
            response.user_role.role = response.answer
        return response

    def _on_set_user_role(self, request: SetUserRole.Request, response: SetUserRole.Response) -> SetUserRole.Response:
        role = request.user_role.role
        response.success, response.answer = self.run(Command(f'setUserRole {role}',
                                                             f'Setting user role: {re.escape(role)}'))
        return response

    def _on_get_operational_mode(self, request, response: GetOperationalMode.Response) -> GetOperationalMode.Response:
        if self._query('get operational mode', r'(NONE|MANUAL|AUTOMATIC)', response):
            response.operational_mode.mode = response.answer
        return response

    def _on_set_operational_mode(self, request: SetOperationalMode.Request,
                                 response: SetOperationalMode.Response) -> SetOperationalMode.Response:
        mode = request.operational_mode.mode
        response.success, response.answer = self.run(Command(f'set operational mode {mode}',
                                                             f'(?:Operational mode ).*(?:{re.escape(mode)}).*'))
        return response

    def _on_flight_report(self, request: GenerateFlightReport.Request,
                          response: GenerateFlightReport.Response) -> GenerateFlightReport.Response:
        response.success, response.answer = self.run(Command(f'generate flight report {request.report_type}',
                                                             r'(?:Flight Report generated with id:).*'))
        if response.success:
            response.report_id = response.answer.split('id: ', 1)[-1]
        return response

    def _on_support_file(self, request: GenerateSupportFile.Request,
                         response: GenerateSupportFile.Response) -> GenerateSupportFile.Response:
        response.success, response.answer = self.run(Command(f'generate support file {request.dir_path}',
                                                             r'(?:Completed successfully:).*'))
        if response.success:
            response.generated_file_name = response.answer.split('Completed successfully: ', 1)[-1]
        return response

    def _not_implemented(self, request, response):
        response.answer, response.success = NOT_IMPLEMENTED, False
        return response
