"""The driver's robot_state_helper, its decisions without ROS: how a SetMode goal brings the robot to a mode.

Facts from ``ur_robot_driver/src/robot_state_helper.cpp`` at the pinned commit (the code is ours):

* targets POWER_OFF, IDLE and RUNNING can be selected; the other modes "cannot be explicitly selected", any other
  number is an "illegal mode";
* ``stop_program`` stops a running program first;
* when the robot is not in the target mode, or its safety mode is worse than REDUCED, the safety is recovered
  first: a protective stop is unlocked, a violation or fault restarts the safety (through the dashboard), an
  emergency stop cannot be recovered ("Please release the EM-Stop to proceed.");
* then, by the current robot mode: from POWER_OFF and IDLE the target's command is sent (POWER_OFF: power off,
  IDLE: power on, RUNNING: brake release); from RUNNING the same, except that IDLE is reached by powering off and
  on again; in CONFIRM_SAFETY, BOOTING, POWER_ON, BACKDRIVE and other modes the helper only says why it cannot act,
  and the goal fails ("Transition to target mode failed.");
* it then waits for the target mode; reached, RUNNING with ``play_program`` and no program running, the program is
  started: resend_robot_program in headless mode, the dashboard's play otherwise.
"""
from __future__ import annotations

from dataclasses import dataclass

from ur_sim_driver.robot.robot_state import (
    BACKDRIVE,
    BOOTING,
    CONFIRM_SAFETY,
    DISCONNECTED,
    FAULT,
    IDLE,
    NO_CONTROLLER,
    POWER_OFF,
    POWER_ON,
    PROTECTIVE_STOP,
    REDUCED,
    ROBOT_EMERGENCY_STOP,
    ROBOT_MODE_NAMES,
    RUNNING,
    SAFETY_MODE_NAMES,
    SYSTEM_EMERGENCY_STOP,
    VIOLATION,
)

UPDATING_FIRMWARE = 8  # urcl::RobotMode, not in ur_dashboard_msgs/RobotMode
SELECTABLE = (POWER_OFF, IDLE, RUNNING)
NOT_SELECTABLE = (NO_CONTROLLER, DISCONNECTED, CONFIRM_SAFETY, BOOTING, POWER_ON, BACKDRIVE, UPDATING_FIRMWARE)
TRANSITION_FAILED = 'Transition to target mode failed.'
REACHED = 'Reached target robot mode.'
# The robot command that brings the robot to each target from POWER_OFF or IDLE (RobotState's method names).
_JUMP = {POWER_OFF: 'power_off', IDLE: 'power_on', RUNNING: 'brake_release'}


def mode_name(mode: int) -> str:
    return 'UPDATING_FIRMWARE' if mode == UPDATING_FIRMWARE else ROBOT_MODE_NAMES.get(mode, str(mode))


def target_refusal(target: int) -> str | None:
    """Why `target` cannot be requested, or None."""
    if target in SELECTABLE:
        return None
    if target in NOT_SELECTABLE:
        return f'Requested target mode {mode_name(target)} which cannot be explicitly selected.'
    return 'Requested illegal mode.'


@dataclass(frozen=True)
class Transition:
    """What the helper does to move towards a target: robot commands (RobotState method names), in order, or
    `fails` with the line it logs."""

    commands: tuple[str, ...] = ()
    fails: bool = False
    log: str = ''


def needs_transition(robot_mode: int, safety_mode: int, target: int) -> bool:
    return robot_mode != target or safety_mode > REDUCED


def safety_recovery(safety_mode: int) -> Transition:
    """The commands that recover the safety mode first (none needed: empty)."""
    if safety_mode == PROTECTIVE_STOP:
        return Transition(('unlock_protective_stop',))
    if safety_mode in (SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP):
        return Transition(fails=True, log=f'The robot is currently in safety mode.{SAFETY_MODE_NAMES[safety_mode]}. '
                                          'Please release the EM-Stop to proceed.')
    if safety_mode in (VIOLATION, FAULT):
        return Transition(('restart_safety',))
    return Transition()


def mode_transition(robot_mode: int, target: int) -> Transition:
    """The commands that take the robot from `robot_mode` towards `target` (after the safety is recovered)."""
    current = mode_name(robot_mode)
    if robot_mode in (POWER_OFF, IDLE):
        return Transition((_JUMP[target],))
    if robot_mode == RUNNING:
        return Transition(('power_off', 'power_on') if target == IDLE else (_JUMP[target],))
    if robot_mode == CONFIRM_SAFETY:
        log = (f'The robot is currently in mode {current}. It is required to interact with the teach pendant at this '
               'point.')
    elif robot_mode == BOOTING:
        log = f'The robot is currently in mode {current}. Please wait until the robot is booted up...'
    elif robot_mode == POWER_ON:
        log = f'The robot is currently in mode {current}. Please wait until the robot is in mode IDLE'
    elif robot_mode == BACKDRIVE:
        log = (f'The robot is currently in mode {current}. It will automatically return to mode IDLE once the teach '
               'button is released.')
    else:
        log = (f"The robot is currently in mode {current}. This won't be handled by this helper. Please resolve this "
               'manually.')
    return Transition(fails=True, log=log)
