"""The controller manager's switch rules (ros2_control jazzy 4.46), with the UR hardware's mode check."""
from __future__ import annotations

import pytest

from ur_sim_driver.controllers import hardware_component as hc
from ur_sim_driver.controllers import ur_hardware as hw
from ur_sim_driver.controllers.controller_manager import (
    ABORT_STRICT,
    ABORT_STRICT_UNKNOWN,
    BEST_EFFORT,
    FORCE_AUTO,
    HARDWARE_REJECTED,
    NOTHING_TO_DO,
    STRICT,
    SWITCHED,
    ControllerManager,
    ControllerSpec,
)
from ur_sim_driver.robot.software import SoftwareVersion

JOINTS = tuple(f'p_{j}' for j in ('a', 'b', 'c', 'd', 'e', 'f'))
PREFIX = 'p_'
POS = hw.joint_interfaces(JOINTS, 'position')
VEL = hw.joint_interfaces(JOINTS, 'velocity')
PASS = tuple(i for i in hw.command_interfaces(JOINTS, PREFIX) if 'trajectory_passthrough' in i)
FREE = tuple(i for i in hw.command_interfaces(JOINTS, PREFIX) if 'freedrive_mode' in i)
TOOL = (f'{PREFIX}tool_contact/tool_contact_set_state',)


def _manager(active=('scaled', 'jsb')) -> ControllerManager:
    specs = [
        ControllerSpec('jsb', 'joint_state_broadcaster/JointStateBroadcaster',
                       state_interfaces=hw.joint_interfaces(JOINTS, 'position', 'velocity', 'effort')),
        ControllerSpec('scaled', 'ur_controllers/ScaledJointTrajectoryController', POS, stops_with_program=True),
        ControllerSpec('jtc', 'joint_trajectory_controller/JointTrajectoryController', POS, stops_with_program=True),
        ControllerSpec('fpc', 'position_controllers/JointGroupPositionController', POS, stops_with_program=True),
        ControllerSpec('fvc', 'velocity_controllers/JointGroupVelocityController', VEL, stops_with_program=True),
        ControllerSpec('pass', 'ur_controllers/PassthroughTrajectoryController', PASS, stops_with_program=True),
        ControllerSpec('free', 'ur_controllers/FreedriveModeController', FREE, unavailable='not on this robot'),
        ControllerSpec('tool', 'ur_controllers/ToolContactController', TOOL, stops_with_program=True),
    ]
    return ControllerManager(specs, active, lambda s, p, r: hw.prepare_command_mode_switch(s, p, r, PREFIX))


def _texts(plan) -> list[str]:
    return [line.text for line in plan.log]


def _switch(cm, activate=(), deactivate=(), strictness=STRICT):
    plan = cm.plan(activate, deactivate, strictness)
    if plan.activate or plan.deactivate:
        cm.apply(plan)
    return plan


def test_start_states_and_claims():
    cm = _manager()
    assert cm.active_names() == ('jsb', 'scaled')
    assert cm.state('jtc') == 'inactive' and cm.claimed('jtc') == ()
    assert cm.claimed('scaled') == POS and cm.claimed('jsb') == ()
    assert set(cm.claimed_interfaces()) == set(POS)


def test_plain_switch_deactivates_then_activates():
    cm = _manager()
    plan = _switch(cm, activate=['fpc'], deactivate=['scaled'])
    assert plan.ok and plan.deactivate == ('scaled',) and plan.activate == ('fpc',)
    assert plan.message == SWITCHED  # STRICT: no lists appended
    assert cm.active_names() == ('jsb', 'fpc')
    plan = _switch(cm, activate=['scaled', 'tool'], deactivate=['fpc'], strictness=BEST_EFFORT)
    assert plan.message == (f'{SWITCHED}\nDeactivated controllers: [ fpc ]\n'
                            'Activated controllers: [ scaled tool ]')


def test_unknown_name_strict_fails_as_a_whole():
    cm = _manager()
    plan = _switch(cm, activate=['nope'], deactivate=['scaled'])
    assert not plan.ok and cm.is_active('scaled')
    text = "Could not activate controller with name 'nope' because no controller with this name exists"
    assert _texts(plan) == [text, ABORT_STRICT_UNKNOWN] and plan.message == text


def test_unknown_name_best_effort_does_the_rest():
    cm = _manager()
    plan = _switch(cm, activate=['nope', 'fpc'], deactivate=['scaled'], strictness=BEST_EFFORT)
    assert plan.ok and plan.activate == ('fpc',) and cm.is_active('fpc') and not cm.is_active('scaled')
    # A list none of whose names exist fails (upstream: the result of its last name, with nothing found before).
    plan = _switch(cm, deactivate=['ghost', 'nope'], strictness=BEST_EFFORT)
    assert not plan.ok and plan.message.count('because no controller with this name exists\n') == 2
    assert cm.is_active('fpc')


def test_activating_an_active_controller():
    cm = _manager()
    strict = _switch(cm, activate=['scaled'])
    assert not strict.ok and strict.message == "Controller with name 'scaled' is already active."
    assert _texts(strict)[-1] == ABORT_STRICT
    best = _switch(cm, activate=['scaled'], strictness=BEST_EFFORT)
    assert best.ok and best.activate == () and best.message == NOTHING_TO_DO
    # In both lists it is restarted: deactivated, then activated, keeping its interfaces.
    plan = _switch(cm, activate=['scaled'], deactivate=['scaled'])
    assert plan.ok and plan.deactivate == ('scaled',) and plan.activate == ('scaled',) and cm.is_active('scaled')


def test_unconfigured_controller_cannot_be_activated():
    cm = _manager()
    cm.states['jtc'] = 'unconfigured'
    plan = _switch(cm, activate=['jtc'], deactivate=['scaled'])
    assert not plan.ok and plan.message.startswith("Controller with name 'jtc' is in 'unconfigured' state.")
    assert cm.is_active('scaled')


def test_deactivating_an_inactive_controller():
    cm = _manager()
    strict = _switch(cm, deactivate=['jtc', 'scaled'])
    assert not strict.ok and cm.is_active('scaled')
    assert strict.message == "Controller with name 'jtc' can not be deactivated since it is not active."
    best = _switch(cm, deactivate=['jtc', 'scaled'], strictness=BEST_EFFORT)
    assert best.ok and best.deactivate == ('scaled',) and not cm.is_active('scaled')
    # All already inactive: nothing to do, which succeeds (the driver's tests rely on it).
    again = _switch(cm, deactivate=['jtc', 'scaled', 'fpc'], strictness=BEST_EFFORT)
    assert again.ok and again.message == NOTHING_TO_DO


def test_conflicting_claims_are_refused_whatever_the_strictness():
    cm = _manager()
    for strictness in (STRICT, BEST_EFFORT):
        # scaled keeps its position interfaces: the forward position controller cannot claim them.
        plan = _switch(cm, activate=['fpc'], strictness=strictness)
        assert not plan.ok and not cm.is_active('fpc')
        assert plan.message == (f"Unable to activate controller 'fpc' since the command interface '{POS[0]}' is "
                                'currently claimed by another controller.')
    _switch(cm, deactivate=['scaled'])
    for strictness in (STRICT, BEST_EFFORT):  # two that claim the same interfaces in one request
        plan = _switch(cm, activate=['scaled', 'jtc', 'tool'], strictness=strictness)
        assert not plan.ok and 'will be used by another controller that is being activated' in plan.message
    assert cm.active_names() == ('jsb',)


def test_hardware_modes_refuse_whatever_the_strictness():
    cm = _manager()
    _switch(cm, deactivate=['scaled'])
    for pair in (['scaled', 'fvc'], ['scaled', 'pass'], ['fpc', 'fvc'], ['fvc', 'pass']):
        for strictness in (STRICT, BEST_EFFORT):
            plan = _switch(cm, activate=pair, strictness=strictness)
            assert not plan.ok, pair
            assert plan.message == HARDWARE_REJECTED and 'is not allowed' in _texts(plan)[-2]
    assert cm.active_names() == ('jsb',)
    # A running position controller excludes velocity unless it is deactivated in the same request.
    _switch(cm, activate=['fpc'])
    assert not _switch(cm, activate=['fvc'], strictness=BEST_EFFORT).ok
    assert _switch(cm, activate=['fvc'], deactivate=['fpc']).ok


def test_tool_contact_runs_beside_position_and_passthrough():
    cm = _manager(active=())
    assert _switch(cm, activate=['scaled', 'tool']).ok
    assert _switch(cm, deactivate=['scaled', 'tool']).ok
    assert _switch(cm, activate=['pass', 'tool']).ok


def test_failed_activation_fails_the_request():
    cm = _manager(active=('scaled',))
    strict = _switch(cm, activate=['free', 'jsb'], deactivate=['scaled'])
    assert not strict.ok and 'not on this robot' in _texts(strict)[0]
    assert strict.message == 'Failed switching controllers.... \nUnable to activate controllers: [ free  ]'
    # The deactivation is done; with STRICT every activation of the request is undone.
    assert cm.active_names() == ()
    best = _switch(cm, activate=['free', 'jsb'], strictness=BEST_EFFORT)
    assert not best.ok and best.activate == ('jsb',) and cm.active_names() == ('jsb',)


def test_inactive_or_unconfigured_hardware_blocks_commanding_controllers():
    hardware = hc.HardwareComponent('ur5e', 'plugin', hw.command_interfaces(JOINTS, PREFIX),
                                    hw.joint_interfaces(JOINTS, 'position', 'velocity', 'effort'))
    specs = [ControllerSpec('jsb', 'jsb', state_interfaces=hw.joint_interfaces(JOINTS, 'position')),
             ControllerSpec('fpc', 'fpc', POS)]
    cm = ControllerManager(specs, (), lambda s, p, r: None, hardware)
    assert hardware.set_state(hc.INACTIVE).ok
    plan = _switch(cm, activate=['fpc'])
    assert not plan.ok and plan.message == HARDWARE_REJECTED
    assert "Component 'ur5e' is in INACTIVE state, but has start interfaces to switch" in _texts(plan)[0]
    assert _switch(cm, activate=['jsb']).ok  # state interfaces are still available
    assert _switch(cm, deactivate=['jsb']).ok
    assert hardware.set_state(hc.UNCONFIGURED).ok
    plan = _switch(cm, activate=['fpc'])
    assert plan.message == (f"Unable to activate controller 'fpc' since the command interface '{POS[0]}' is not "
                            'available.')
    plan = _switch(cm, activate=['jsb'])
    assert plan.message == (f"Unable to activate controller 'jsb' since the state interface '{POS[0]}' is not "
                            'available.')
    assert hardware.set_state(hc.ACTIVE).ok and _switch(cm, activate=['fpc', 'jsb']).ok
    assert cm.is_claimed(POS[0])
    assert hardware.set_state(hc.UNCONFIGURED).ok
    assert not cm.is_claimed(POS[0]) and cm.is_active('fpc')  # unavailable: never claimed, the controller runs on


def test_strictness_zero_is_best_effort_and_bad_values_fail():
    cm = _manager()
    plan = _switch(cm, activate=['tool', 'nope'], strictness=0)
    assert plan.ok and 'Defaulting to BEST_EFFORT' in _texts(plan)[0] and cm.is_active('tool')
    assert _switch(cm, activate=['nope'], deactivate=['tool'], strictness=FORCE_AUTO).ok is False
    bad = _switch(cm, activate=['fpc'], deactivate=['scaled'], strictness=7)
    assert not bad.ok and 'strictness = 7' in bad.message and cm.is_active('scaled')


def test_empty_request_succeeds():
    plan = _switch(_manager(), strictness=STRICT)
    assert plan.ok and plan.message == NOTHING_TO_DO


def test_stale_plan_is_refused():
    cm = _manager()
    plan = cm.plan(['fpc'], ['scaled'], STRICT)
    cm.apply(plan)
    with pytest.raises(ValueError, match='stale switch plan'):
        cm.apply(plan)


def test_stoppable_and_bad_construction():
    cm = _manager()
    assert cm.stoppable_active() == ('scaled',)
    with pytest.raises(ValueError, match='already claimed'):
        _manager(active=('scaled', 'jtc'))
    with pytest.raises(ValueError, match='not loaded'):
        _manager(active=('ghost',))
    with pytest.raises(ValueError, match='loaded twice'):
        ControllerManager([ControllerSpec('a', 't'), ControllerSpec('a', 't')])


def test_hardware_mode_table():
    assert hw.mode_of(POS[0], PREFIX) == 'position' and hw.mode_of(VEL[3], PREFIX) == 'velocity'
    assert hw.mode_of(PASS[0], PREFIX) == 'trajectory_passthrough' and hw.mode_of(FREE[1], PREFIX) == 'freedrive_mode'
    assert hw.mode_of(f'{PREFIX}gpio/tool_voltage_cmd', PREFIX) is None
    assert hw.compatible('position', 'tool_contact') and hw.compatible('force_mode', 'trajectory_passthrough')
    assert not hw.compatible('freedrive_mode', 'tool_contact') and not hw.compatible('position', 'velocity')
    assert hw.prepare_command_mode_switch(VEL, POS, POS, PREFIX) is None
    assert hw.prepare_command_mode_switch(VEL, (), POS, PREFIX) == \
        'Starting velocity together with position is not allowed.'
    assert set(POS) | set(VEL) <= set(hw.command_interfaces(JOINTS, PREFIX))


def test_effort_needs_torque_control():
    eff = hw.joint_interfaces(JOINTS, 'effort')
    assert hw.prepare_command_mode_switch(eff, (), (), PREFIX, SoftwareVersion(5, 12, 6)) == hw.EFFORT_TOO_OLD
    assert hw.prepare_command_mode_switch(eff, (), (), PREFIX, SoftwareVersion(3, 15, 8)) == hw.EFFORT_TOO_OLD
    # New enough: alone, or in the switch that stops the position controller; not beside it.
    assert hw.prepare_command_mode_switch(eff, (), (), PREFIX, SoftwareVersion(5, 23, 0)) is None
    assert hw.prepare_command_mode_switch(eff, (), (), PREFIX, SoftwareVersion(10, 10, 0)) is None
    assert hw.prepare_command_mode_switch(eff, POS, POS, PREFIX, SoftwareVersion(5, 23, 0)) is None
    assert hw.prepare_command_mode_switch(eff, (), POS, PREFIX, SoftwareVersion(5, 23, 0)) == \
        'Starting effort together with position is not allowed.'
    # Incompatible modes are named first, as upstream checks them first.
    assert hw.prepare_command_mode_switch(eff + POS, (), (), PREFIX, SoftwareVersion(5, 12, 6)) == \
        'Starting position together with effort is not allowed.'
    assert hw.mode_of(hw.friction_interfaces(PREFIX)[0], PREFIX) is None  # the friction model starts no mode
