"""User role (CB3) and operational mode (PolyScope 5) as state that restricts what the robot accepts: an e-series in
MANUAL mode is in local control and refuses the dashboard commands that act on it, with the robot's answer; a CB3's
user role restricts its teach pendant but not its dashboard. The interpreter alone, then over DDS."""
import pytest
from dashboard_helpers import DashboardServices
from sim_harness import running_sim
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import OperationalMode, UserRole
from ur_dashboard_msgs.srv import (
    GetOperationalMode,
    GetRobotMode,
    GetUserRole,
    IsInRemoteControl,
    Load,
    RawRequest,
    SetOperationalMode,
    SetUserRole,
)

from ur_sim_driver.robot.dashboard_roles import PENDANT_ACTIONS, REMOTE_ONLY, REMOTE_REFUSAL, OperatorControls
from ur_sim_driver.robot.dashboard_server import DashboardServer
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.software import CB3_VERSION, COMMANDS, E_SERIES_VERSION

ACTING = ('power on', 'power off', 'brake release', 'unlock protective stop', 'restart safety', 'load wait_program.urp',
          'load installation default.installation', 'play', 'pause', 'stop', 'shutdown')


def server(version) -> DashboardServer:
    return DashboardServer(RobotState(programs=('wait_program.urp',)), 'ur5e' if version.e_series else 'ur10', version)


def test_every_restricted_command_is_a_dashboard_command():
    assert REMOTE_ONLY <= set(COMMANDS)


def test_manual_mode_is_local_control_and_refuses_what_acts_on_the_robot():
    s = server(E_SERIES_VERSION)
    assert s.handle('is in remote control').answer == 'true'
    assert s.handle('set operational mode manual').answer == "Operational mode 'manual' is set"
    assert s.handle('is in remote control').answer == 'false'
    for line in ACTING:
        reply = s.handle(line)
        assert reply.answer == REMOTE_REFUSAL and 'local control' in reply.refusal, line
    assert s.robot.program_state == 'PLAYING' and s.robot.robot_mode == 7  # nothing changed: RUNNING, playing
    # Queries, popups and the operational mode stay available in local control.
    for line, answer in (('robotmode', 'Robotmode: RUNNING'), ('popup hello', 'showing popup'),
                         ('get operational mode', 'MANUAL'), ('close popup', 'closing popup')):
        assert s.handle(line).answer == answer, line
    assert s.handle('clear operational mode').answer.endswith("Current operational mode: 'MANUAL'.")
    assert s.handle('play').answer == REMOTE_REFUSAL  # clearing leaves the mode as it is
    assert s.handle('set operational mode AUTOMATIC').answer == "Operational mode 'AUTOMATIC' is set"
    assert s.handle('is in remote control').answer == 'true'
    assert s.handle('stop').answer == 'Stopped'


def test_a_cb3_user_role_leaves_the_dashboard_as_it_is():
    s = server(CB3_VERSION)
    for role in ('locked', 'operator', 'restricted', 'programmer', 'none'):
        assert s.handle(f'setUserRole {role}').answer == f'Setting user role: {role}'
        assert s.handle('getUserRole').answer == role.upper()
        assert s.handle('stop').answer == 'Stopped' and s.handle('play').answer == 'Starting program'
    assert s.handle('setUserRole').answer == 'Setting user role: none'  # no role: NONE, as UR documents
    assert s.handle('getUserRole').answer == 'NONE'
    reply = s.handle('setUserRole boss')
    assert reply.answer == "Failed setting user role: 'boss'" and 'programmer' in reply.refusal
    assert s.handle('getUserRole').answer == 'NONE'


@pytest.mark.parametrize('role, allowed', [
    ('NONE', set(PENDANT_ACTIONS)), ('PROGRAMMER', set(PENDANT_ACTIONS) - {'setup robot'}),
    ('OPERATOR', {'run program', 'shutdown robot'}), ('RESTRICTED', {'run program', 'shutdown robot'}),
    ('LOCKED', set())])
def test_the_user_role_restricts_the_teach_pendant(role, allowed):
    controls = OperatorControls(e_series=False)
    assert controls.set_user_role(role.lower()) is None
    assert {a for a in PENDANT_ACTIONS if controls.pendant_allows(a)} == allowed
    with pytest.raises(ValueError, match='is not one of'):
        controls.pendant_allows('fly')


def test_a_cb3_is_always_in_remote_control():
    controls = OperatorControls(e_series=False)
    controls.operational_mode = 'MANUAL'  # a CB3 has no operational mode: nothing can set it; nothing depends on it
    assert controls.remote_control and controls.refusal('play') is None


# ---- over DDS ---------------------------------------------------------------------------------------------------
SERVICES = {'set_operational_mode': SetOperationalMode, 'get_operational_mode': GetOperationalMode,
            'is_in_remote_control': IsInRemoteControl, 'power_off': Trigger, 'play': Trigger, 'stop': Trigger,
            'load_program': Load, 'get_robot_mode': GetRobotMode, 'set_user_role': SetUserRole,
            'get_user_role': GetUserRole, 'raw_request': RawRequest, 'clear_operational_mode': Trigger}


@pytest.fixture(scope='module', params=['ur5e', 'ur10'])
def robot(request):
    with running_sim(ur_type=request.param) as h:
        services = DashboardServices(h, SERVICES)
        yield h, services


def test_manual_mode_refuses_the_driver_services_that_act_on_the_robot(robot):
    h, s = robot
    if not h.sim.cfg.software_version.e_series:
        pytest.skip('a CB3 has no operational mode (test_dashboard_versions covers its refusal)')
    try:
        assert s.call('set_operational_mode', operational_mode=OperationalMode(mode='MANUAL')).success
        assert s.call('get_operational_mode').operational_mode.mode == 'MANUAL'
        r = s.call('is_in_remote_control')
        assert r.success and not r.remote_control
        for name, expected in (('power_off', 'Powering off'), ('stop', 'Stopped')):
            r = s.call(name)
            assert (r.success, r.message) == (False, f'Expected: {expected}, but received: {REMOTE_REFUSAL}'), name
        r = s.call('load_program', filename='wait_program.urp')
        assert not r.success and r.answer.endswith(f'but received: {REMOTE_REFUSAL}')
        assert s.call('raw_request', query='play').answer == REMOTE_REFUSAL  # raw lines meet the same robot
        r = s.call('get_robot_mode')
        assert r.success and r.robot_mode.mode == 7  # still RUNNING: nothing acted on the robot
        assert s.call('clear_operational_mode').success
        assert s.call('set_operational_mode', operational_mode=OperationalMode(mode='AUTOMATIC')).success
        assert s.call('is_in_remote_control').remote_control
        assert s.call('stop').success
    finally:
        s.call('set_operational_mode', operational_mode=OperationalMode(mode='AUTOMATIC'))
        s.call('play')


def test_a_cb3_user_role_is_the_robots_and_leaves_its_dashboard_usable(robot):
    h, s = robot
    if h.sim.cfg.software_version.e_series:
        pytest.skip('user roles are CB3 only (test_dashboard_versions covers the e-series refusal)')
    try:
        r = s.call('set_user_role', user_role=UserRole(role=UserRole.LOCKED))
        assert r.success and r.answer == 'Setting user role: LOCKED'
        assert s.call('get_user_role').user_role.role == UserRole.LOCKED
        assert h.sim.host.dashboard.controls.pendant_allows('run program') is False
        assert s.call('stop').success  # the dashboard is not the teach pendant: LOCKED does not restrict it
        assert s.call('raw_request', query='setUserRole').answer == 'Setting user role: none'
        assert s.call('get_user_role').user_role.role == UserRole.NONE
    finally:
        s.call('set_user_role', user_role=UserRole(role=UserRole.PROGRAMMER))
        s.call('play')
