"""The driver's dashboard commands as data: what each `/dashboard_client/*` Trigger service sends, the answer it
expects, and the robot state it then waits for (ur_robot_driver 3.8's ``dashboard_client_ros.cpp`` over the
Universal Robots Client Library), with the client's fixed messages. No rclpy here.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

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
NOT_IMPLEMENTED = 'Not implemented for this robot software version.'
# ur_dashboard_msgs/SafetyStatus by the name in a `safetystatus` answer (the driver maps VALIDATE_JOINT to its _ID)
SAFETY_STATUS_BY_NAME = {name: mode for mode, name in SAFETY_MODE_NAMES.items()} | {'VALIDATE_JOINT': 10}
ROBOT_MODES_BY_NAME = {name: mode for mode, name in ROBOT_MODE_NAMES.items()}
SAFETY_MODES_BY_NAME = {name: mode for mode, name in SAFETY_MODE_NAMES.items()}


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
