"""The driver's `dashboard_client` node: `/dashboard_client/*` services in front of the robot's dashboard server.

In the real driver (ur_robot_driver 3.8, ``dashboard_client_ros.cpp`` over the Universal Robots Client
Library) each service sends one command line to the robot's dashboard server and checks the answer; commands
that change the robot also wait until the robot reports the new state (power on: robot mode IDLE or RUNNING;
brake release and unlock: RUNNING; play / pause / stop: the program state; load: STOPPED <program>). A
service therefore returns once the robot is there, so `power_on`, `brake_release`, `play` can be called one
after the other. `message` / `answer` is the server's answer; when the answer is not the expected one it is
the client library's "Expected: <pattern>, but received: <answer>". ur_sim does the same against
:class:`~ur_sim_driver.robot.dashboard_server.DashboardServer`, waiting in simulated time.
"""
from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from rclpy.node import Node
from std_srvs.srv import Trigger
from ur_dashboard_msgs.srv import (
    AddToLog,
    GetLoadedProgram,
    GetProgramState,
    GetRobotMode,
    GetSafetyMode,
    IsInRemoteControl,
    IsProgramRunning,
    IsProgramSaved,
    Load,
    Popup,
    RawRequest,
)

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.robot.dashboard_server import DashboardServer
from ur_sim_driver.robot.robot_state import (
    IDLE,
    PAUSED,
    PLAYING,
    POWER_OFF,
    ROBOT_MODE_NAMES,
    RUNNING,
    SAFETY_MODE_NAMES,
    STOPPED,
    RobotState,
)

WAIT_TIMEOUT = 5.0  # [s] of simulated time the client waits for the robot to reach a commanded state
POWER_ON_TIMEOUT = 300.0  # [s] the driver's power_on service waits for IDLE
STALL_TIMEOUT = 2.0  # [s] of wall time without simulated time advancing: the simulation is not running
NOT_CONNECTED = 'Failed to send request to dashboard server. Are you connected to the Dashboard Server?'
_ROBOT_MODES = {name: mode for mode, name in ROBOT_MODE_NAMES.items()}
_SAFETY_MODES = {name: mode for mode, name in SAFETY_MODE_NAMES.items()}


class NotConnected(Exception):
    """The client is disconnected (after `quit` or `shutdown`)."""


@dataclass(frozen=True)
class Command:
    """One dashboard service as the driver runs it.

    Attributes:
        line: the command line sent to the server.
        expected: regular expression the answer must match in full.
        until: robot-state condition waited for after a matching answer (None: no wait).
        failed: message when the condition is not reached in time.
        timeout: [s] of simulated time to wait.
        strict: False when the driver reports success even if the wait ran out (stop).
    """

    line: str
    expected: str
    until: Callable[[RobotState], bool] | None = None
    failed: str = ''
    timeout: float = WAIT_TIMEOUT
    strict: bool = True


def _expected_state(what: str, state: str) -> str:
    return f"Failed to {what} program. Expected 'programState' to be '{state}', but did not receive such a message."


TRIGGERS = {
    'power_on': Command('power on', 'Powering on', lambda r: r.robot_mode in (IDLE, RUNNING),
                        "Failed to get expected response for command 'power on' within the timeout. "
                        'Last response was: Powering on', POWER_ON_TIMEOUT),
    'power_off': Command('power off', 'Powering off', lambda r: r.robot_mode == POWER_OFF, 'Powering off'),
    'brake_release': Command('brake release', 'Brake releasing', lambda r: r.robot_mode == RUNNING,
                             "Failed to release brakes. Expected 'robotmode' to be 'RUNNING', but did not receive it."),
    'play': Command('play', 'Starting program', lambda r: r.program_state == PLAYING,
                    _expected_state('play', PLAYING)),
    'pause': Command('pause', 'Pausing program', lambda r: r.program_state == PAUSED,
                     _expected_state('pause', PAUSED)),
    'stop': Command('stop', 'Stopped', lambda r: r.program_state == STOPPED, _expected_state('stop', STOPPED),
                    strict=False),
    'unlock_protective_stop': Command(
        'unlock protective stop', 'Protective stop releasing', lambda r: r.robot_mode == RUNNING,
        "Failed to unlock the protective stop. Expected 'robotmode' to be 'RUNNING', but did not receive it."),
    'restart_safety': Command('restart safety', 'Restarting safety', lambda r: r.robot_mode == POWER_OFF,
                              "Failed to power off the robot. Expected 'robotmode' to be 'POWER_OFF', but did not "
                              'receive such a message.'),
    'close_popup': Command('close popup', 'closing popup'),
    'close_safety_popup': Command('close safety popup', 'closing safety popup'),
    'clear_operational_mode': Command('clear operational mode', r'No longer controlling the operational mode\..*'),
    'shutdown': Command('shutdown', 'Shutting down'),
    'quit': Command('quit', 'Disconnected'),
}


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
        self.server = DashboardServer(host.robot)
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

    def run(self, command: Command) -> tuple[bool, str]:
        """Send `command`, check its answer and wait for its state: (success, message)."""
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
            response.robot_mode.mode = _ROBOT_MODES[match[1]]
        return response

    def _on_safety_mode(self, request, response: GetSafetyMode.Response) -> GetSafetyMode.Response:
        match = self._query('safetymode', r'Safetymode: (.*)', response)
        if match:
            response.safety_mode.mode = _SAFETY_MODES[match[1]]
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
