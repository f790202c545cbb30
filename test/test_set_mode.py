"""The robot_state_helper's decisions (set_mode.py): which targets, which recovery, which commands from each mode."""
from __future__ import annotations

import pytest

from ur_sim_driver.controllers import set_mode as sm
from ur_sim_driver.robot.robot_state import (
    BACKDRIVE,
    BOOTING,
    FAULT,
    IDLE,
    NORMAL,
    POWER_OFF,
    POWER_ON,
    PROTECTIVE_STOP,
    REDUCED,
    ROBOT_EMERGENCY_STOP,
    RUNNING,
    SAFEGUARD_STOP,
)


def test_targets():
    assert all(sm.target_refusal(t) is None for t in (POWER_OFF, IDLE, RUNNING))
    assert sm.target_refusal(BOOTING) == 'Requested target mode BOOTING which cannot be explicitly selected.'
    assert sm.target_refusal(8) == 'Requested target mode UPDATING_FIRMWARE which cannot be explicitly selected.'
    assert sm.target_refusal(-7) == 'Requested illegal mode.'


def test_transition_needed_for_a_worse_safety_mode_too():
    assert not sm.needs_transition(RUNNING, REDUCED, RUNNING)
    assert sm.needs_transition(RUNNING, SAFEGUARD_STOP, RUNNING)
    assert sm.needs_transition(IDLE, NORMAL, RUNNING)


def test_safety_recovery():
    assert sm.safety_recovery(NORMAL) == sm.Transition()
    assert sm.safety_recovery(PROTECTIVE_STOP).commands == ('unlock_protective_stop',)
    assert sm.safety_recovery(FAULT).commands == ('restart_safety',)
    estop = sm.safety_recovery(ROBOT_EMERGENCY_STOP)
    assert estop.fails and estop.log.endswith('Please release the EM-Stop to proceed.')


@pytest.mark.parametrize(('mode', 'target', 'commands'), [
    (POWER_OFF, RUNNING, ('brake_release',)), (POWER_OFF, IDLE, ('power_on',)), (IDLE, POWER_OFF, ('power_off',)),
    (IDLE, RUNNING, ('brake_release',)), (RUNNING, IDLE, ('power_off', 'power_on')),
    (RUNNING, POWER_OFF, ('power_off',)), (RUNNING, RUNNING, ('brake_release',)),
])
def test_commands_from_each_mode(mode, target, commands):
    assert sm.mode_transition(mode, target) == sm.Transition(commands)


@pytest.mark.parametrize(('mode', 'words'), [
    (POWER_ON, 'Please wait until the robot is in mode IDLE'), (BOOTING, 'Please wait until the robot is booted up'),
    (BACKDRIVE, 'once the teach button is released'), (-1, "This won't be handled by this helper"),
])
def test_modes_the_helper_does_not_handle(mode, words):
    step = sm.mode_transition(mode, RUNNING)
    assert step.fails and not step.commands and words in step.log
