"""``/urscript_interface``: the driver's urscript_interface node, on ur_sim's URScript program slot.

As upstream (``urscript_interface.cpp`` with the client library's ``PrimaryClient``):

* ``~/script_command`` (std_msgs/String, depth 1): the text goes to the robot as it is; ignored with an error while
  an action goal runs;
* ``~/execute_script`` (ur_msgs/action/SendScript): one goal at a time (another is rejected: "Action server is
  busy"). The script is prepared as the client library prepares it: comments and blank lines dropped, bare
  statements wrapped in ``def <script_name>():`` (default ``script_<ms since epoch>``), a name of letters, digits
  and underscores. The robot must be RUNNING in NORMAL, REDUCED or RECOVERY safety. The goal succeeds with "Script
  executed successfully" when the program has stopped, at once for a ``sec`` program; a runtime error (ur_sim also
  reports its compile errors so, with line and column) aborts it with the client library's text and the program's
  lines; a cancel stops the program ("Script execution canceled").

Upstream waits `start_timeout` of wall time for the program to start; in ur_sim it starts in the call that sends it.
"""
from __future__ import annotations

import re
import threading
import time

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.node import Node
from std_msgs.msg import String
from ur_msgs.action import SendScript

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.errors import ScriptError
from ur_sim_driver.robot.robot_state import (
    NORMAL,
    RECOVERY,
    REDUCED,
    ROBOT_MODE_NAMES,
    RUNNING,
    SAFETY_MODE_NAMES,
)
from ur_sim_driver.urscript.runner import RUNTIME_ERROR, STOPPED, ScriptEvent

_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*$')
MAX_NAME = 31  # the client library truncates longer script names


def prepare_script(program: str, script_name: str, now_ms: int) -> tuple[str, str, bool]:
    """(name, code, secondary) as the client library's prepareScript makes them; ScriptError when it refuses."""
    lines = [line for line in program.split('\n') if line.strip() and not line.strip().startswith('#')]
    if not lines:
        raise ScriptError('Script is empty after stripping comments and whitespace.')
    head = lines[0][:4]
    secondary = False
    if 'def ' not in head and 'sec ' not in head:
        name = (script_name or f'script_{now_ms}')[:MAX_NAME]
        lines = [f'def {name}():', *('  ' + line for line in lines), 'end']
    else:
        if '(' not in lines[0]:
            raise ScriptError("Function definition detected in script, but a '(' could not be found. Definition "
                              'is invalid.')
        name = lines[0][4:lines[0].index('(')][:MAX_NAME]
        secondary = 'sec ' in head
    if not _NAME.match(name):
        raise ScriptError(f"Invalid script name: '{name}'. Can only contain letters, numbers and underscores. First "
                          'character must be a letter or underscore.')
    if 'end' not in lines[-1][:3]:
        raise ScriptError("Script contains either function definition or secondary process definition, but no 'end' "
                          'term. Script is invalid.')
    return name, '\n'.join(lines) + '\n', secondary


def runtime_error_text(event: ScriptEvent, code: str) -> str:
    """The client library's RobotRuntimeException text: the error, where, and the numbered program."""
    text = (f'Runtime exception occured during script execution.Runtime exception type: {event.text}\n'
            f'Exception occured at line {event.line}, column {event.column}\n')
    lines = code.split('\n')
    width = len(str(len(lines)))
    for i, line in enumerate(lines):
        if line:
            text += f'{i + 1:>{width}}: {line}\n'
        if event.line > 0 and event.column > 0 and i == event.line - 1:
            text += ' ' * (event.column - 1 + width + 2) + '^<--- here\n'
    return text


class _Run:
    """The program of one goal, followed through the runner's events."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.error: ScriptEvent | None = None
        self.stopped = threading.Event()

    def on_event(self, event: ScriptEvent) -> None:
        if event.name != self.name:
            return
        if event.kind == RUNTIME_ERROR:
            self.error = event
        elif event.kind == STOPPED:
            self.stopped.set()


class URScriptInterface(Component):
    """The script topic and the SendScript action server."""

    name = 'urscript_interface'
    type_name = 'ur_robot_driver/urscript_interface'  # a node of the driver, not a controller
    is_controller = False

    def on_configure(self, host: Host, node: Node) -> None:
        node.declare_parameter('robot_ip', '127.0.0.1')
        node.declare_parameter('retry_on_readonly_interface', True)
        self._busy = False
        self._run: _Run | None = None
        node.create_subscription(String, '~/script_command', self._on_script, 1,
                                 callback_group=ReentrantCallbackGroup())
        ActionServer(node, SendScript, '~/execute_script', execute_callback=self._execute,
                     goal_callback=self._on_goal, cancel_callback=self._on_cancel,
                     callback_group=MutuallyExclusiveCallbackGroup())

    def _on_script(self, msg: String) -> None:
        logger = self.node.get_logger()
        if self._busy:
            logger.error('Script interface is executing action, ignoring topic')
            return
        try:
            program = self.host.scripts.compile(msg.data)  # outside the lock: parsing takes time
            with self.host.lock:
                self.host.scripts.start(program)
        except ScriptError as exc:
            logger.error(f'Could not send program to robot: {exc}')
            return
        logger.info(f'Sent program to robot:\n{msg.data}')

    def _on_goal(self, goal: SendScript.Goal) -> GoalResponse:
        if self._busy:
            self.node.get_logger().error('Action server is busy')
            return GoalResponse.REJECT
        self._busy = True
        return GoalResponse.ACCEPT

    def _on_cancel(self, goal_handle) -> CancelResponse:
        if self._run is None:
            self.node.get_logger().error('Received cancel request for inactive goal, rejecting')
            return CancelResponse.REJECT
        with self.host.lock:
            self.host.scripts.stop()
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle) -> SendScript.Result:
        try:
            return self._execute_goal(goal_handle)
        finally:
            self._run = None
            self._busy = False

    def _execute_goal(self, goal_handle) -> SendScript.Result:
        goal, logger = goal_handle.request, self.node.get_logger()
        try:
            name, code, secondary = prepare_script(goal.program, goal.script_name, int(time.time() * 1000))
            run = _Run(name)
            with self.host.lock:
                self._refuse_unless_running()
            try:
                program = self.host.scripts.compile(code, name)  # outside the lock: parsing takes time
            except ScriptError as exc:  # does not compile: the controller reports it as a runtime exception
                raise ScriptError(runtime_error_text(ScriptEvent(RUNTIME_ERROR, name, str(exc), exc.line,
                                                                 exc.column), code)) from None
            with self.host.lock:
                undo = self.host.scripts.listen(run.on_event)
                self._run = run  # executing: a cancel from here on stops the program
                try:
                    self.host.scripts.start(program)
                except ScriptError:
                    undo()
                    raise
        except ScriptError as exc:
            logger.error(f'Script did not execute successfully. Error message:\n{exc}')
            goal_handle.abort()
            return SendScript.Result(success=False, message=str(exc))
        try:
            if secondary:
                logger.info(f'Script {name} was determined to be a secondary program. Script was transferred '
                            'successfully, but no further feedback will be provided.')
            else:
                run.stopped.wait()
        finally:
            undo()
        if run.error is not None:
            message = runtime_error_text(run.error, code)
            logger.error(f'Script did not execute successfully. Error message:\n{message}')
            goal_handle.abort()
            return SendScript.Result(success=False, message=message)
        if goal_handle.is_cancel_requested:
            goal_handle.canceled()
            return SendScript.Result(success=False, message='Script execution canceled')
        goal_handle.succeed()
        return SendScript.Result(success=True, message='Script executed successfully')

    def _refuse_unless_running(self) -> None:
        robot = self.host.robot
        if robot.robot_mode != RUNNING:
            raise ScriptError('Robot is in incorrect mode for the requested operation: Script execution via primary '
                              f'interface\nRequired robot mode: RUNNING ({RUNNING}) \nActual robot mode: '
                              f'{ROBOT_MODE_NAMES[robot.robot_mode]} ({robot.robot_mode})')
        if robot.safety_mode not in (NORMAL, REDUCED, RECOVERY):
            allowed = ''.join(f'{SAFETY_MODE_NAMES[m]} ({m})\n' for m in (NORMAL, REDUCED, RECOVERY))
            raise ScriptError('Robot is in incorrect safety mode for the requested operation: Script execution via '
                              f'primary interface\nSafety mode should be one of: \n{allowed}UNDEFINED_SAFETY_MODE '
                              f'(11)\n\nActual safety mode: {SAFETY_MODE_NAMES[robot.safety_mode]} '
                              f'({robot.safety_mode})')
