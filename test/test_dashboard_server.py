"""DashboardServer: the robot's dashboard answers (wording of UR's dashboard server) and their effect."""
import json
import zipfile

import pytest

from ur_sim_driver.robot.dashboard_server import UNLOCK_REFUSED, DashboardServer
from ur_sim_driver.robot.robot_state import (
    BRAKE_RELEASE_TIME,
    POWER_ON_TIME,
    UNLOCK_DELAY,
    RobotState,
)
from ur_sim_driver.robot.software import SoftwareVersion


def server(**kw) -> DashboardServer:
    return DashboardServer(RobotState(programs=('wait_program.urp',), **kw))


def answer(s: DashboardServer, line: str) -> str:
    return s.handle(line).answer


def test_start_up_sequence_answers():
    s = server(powered_off=True)
    assert answer(s, 'robotmode') == 'Robotmode: POWER_OFF'
    assert answer(s, 'play') == 'Failed to execute: play'
    assert s.handle('play').refusal is not None
    assert answer(s, 'power on') == 'Powering on'
    assert answer(s, 'robotmode') == 'Robotmode: POWER_ON'
    s.robot.update(POWER_ON_TIME)
    assert answer(s, 'robotmode') == 'Robotmode: IDLE'
    assert answer(s, 'brake release') == 'Brake releasing'
    s.robot.update(POWER_ON_TIME + BRAKE_RELEASE_TIME)
    assert answer(s, 'robotmode') == 'Robotmode: RUNNING'
    assert answer(s, 'programState') == 'STOPPED external_control.urp'
    assert answer(s, 'running') == 'Program running: false'
    assert answer(s, 'play') == 'Starting program'
    assert answer(s, 'programState') == 'PLAYING external_control.urp'
    assert answer(s, 'running') == 'Program running: true'
    assert answer(s, 'power off') == 'Powering off'
    assert answer(s, 'robotmode') == 'Robotmode: POWER_OFF'


def test_program_commands():
    s = server()
    assert answer(s, 'load wait_program.urp') == 'Loading program: /programs/wait_program.urp'
    assert answer(s, 'get loaded program') == 'Loaded program: /programs/wait_program.urp'
    assert answer(s, 'programState') == 'STOPPED wait_program.urp'
    assert answer(s, 'pause') == 'Failed to execute: pause'
    assert answer(s, 'play') == 'Starting program'
    assert answer(s, 'pause') == 'Pausing program'
    assert answer(s, 'programState') == 'PAUSED wait_program.urp'
    assert answer(s, 'stop') == 'Stopped'
    assert answer(s, 'programState') == 'STOPPED wait_program.urp'
    assert answer(s, 'isProgramSaved') == 'true wait_program.urp'
    assert answer(s, 'load bogus.urp') == 'File not found: bogus.urp'
    assert answer(s, 'get loaded program') == 'Loaded program: /programs/wait_program.urp'


def test_installation_popup_log_and_fixed_answers():
    s = server()
    assert answer(s, 'load installation default.installation') == 'Loading installation: /programs/default.installation'
    assert answer(s, 'load installation none.installation') == 'File not found: none.installation'
    assert answer(s, 'popup Hello  there') == 'showing popup'
    assert s.popup == 'Hello  there'
    assert answer(s, 'close popup') == 'closing popup'
    assert s.popup is None
    assert answer(s, 'addToLog glue gun on') == 'Added log message'
    assert answer(s, 'addToLog') == 'No log message to add'
    assert s.log == ['glue gun on']
    assert answer(s, 'close safety popup') == 'closing safety popup'
    assert answer(s, 'is in remote control') == 'true'
    assert answer(s, 'safetymode') == 'Safetymode: NORMAL'
    assert answer(s, 'safetystatus') == 'Safetystatus: NORMAL'
    assert answer(s, 'quit') == 'Disconnected'
    assert answer(s, 'clear operational mode').startswith('No longer controlling the operational mode.')


def test_commands_are_case_insensitive_and_unknown_ones_are_not_understood():
    s = server()
    assert answer(s, 'RobotMode') == 'Robotmode: RUNNING'
    assert answer(s, '  Power   OFF ') == 'Powering off'
    assert answer(s, 'LOAD wait_program.urp') == 'Loading program: /programs/wait_program.urp'
    assert answer(s, 'set_payload(1.0)') == "could not understand: 'set_payload(1.0)'"
    assert answer(s, 'loadx') == "could not understand: 'loadx'"


def test_protective_stop_unlock_and_restart_safety():
    s = server()
    s.robot.update(3.0)
    s.robot.protective_stop(3.0, 'test')
    assert answer(s, 'safetymode') == 'Safetymode: PROTECTIVE_STOP'
    assert answer(s, 'programState') == 'PAUSED external_control.urp'
    assert answer(s, 'unlock protective stop') == UNLOCK_REFUSED
    assert UNLOCK_REFUSED.startswith('Cannot unlock protective stop until 5s after occurrence.')
    s.robot.update(3.0 + UNLOCK_DELAY)
    assert answer(s, 'unlock protective stop') == 'Protective stop releasing'
    assert answer(s, 'safetymode') == 'Safetymode: NORMAL'
    assert answer(s, 'play') == 'Starting program'
    assert answer(s, 'restart safety') == 'Restarting safety'
    assert answer(s, 'robotmode') == 'Robotmode: POWER_OFF'
    assert answer(s, 'shutdown') == 'Shutting down'


def versioned(ur_type: str, files=None, version=None) -> DashboardServer:
    return DashboardServer(RobotState(), ur_type, version, files)


def test_each_series_knows_its_own_commands_only():
    e, cb3 = versioned('ur10e'), versioned('ur10')
    assert answer(e, 'PolyscopeVersion') == 'URSoftware 5.25.1.0 (simulated)'
    assert answer(cb3, 'PolyscopeVersion') == 'URSoftware 3.15.8.0 (simulated)'
    assert answer(e, 'get robot model') == answer(cb3, 'get robot model') == 'UR10'  # no 'e' in the answer
    assert answer(e, 'get serial number').startswith('20') and answer(e, 'get serial number').isdigit()
    for line in ('safetystatus', 'get operational mode', 'is in remote control', 'clear operational mode',
                 'set operational mode manual'):
        assert answer(cb3, line) == f"could not understand: '{line}'"
        assert not answer(e, line).startswith('could not understand')
    for line in ('getUserRole', 'setUserRole operator'):
        assert answer(e, line) == f"could not understand: '{line}'"
        assert not answer(cb3, line).startswith('could not understand')
    old = versioned('ur5e', version=SoftwareVersion(5, 5, 0))
    assert answer(old, 'get serial number') == "could not understand: 'get serial number'"
    assert old.handle('get serial number').refusal == 'software 5.5.0.0 does not know it'


def test_operational_mode_is_set_and_reported():
    s = versioned('ur5e')
    assert answer(s, 'get operational mode') == 'AUTOMATIC'
    assert answer(s, 'set operational mode MANUAL') == "Operational mode 'MANUAL' is set"
    assert answer(s, 'get operational mode') == 'MANUAL'
    assert answer(s, 'clear operational mode').endswith("Current operational mode: 'MANUAL'.")
    reply = s.handle('set operational mode sideways')
    assert reply.answer == "Failed setting operational mode: 'sideways'"
    assert reply.refusal == "operational mode 'sideways' is not one of manual, automatic"
    assert answer(s, 'get operational mode') == 'MANUAL'


@pytest.mark.parametrize('role', ['PROGRAMMER', 'OPERATOR', 'NONE', 'LOCKED', 'RESTRICTED'])
def test_a_cb3_takes_every_user_role(role):
    s = versioned('ur5')
    assert answer(s, f'setUserRole {role}') == f'Setting user role: {role}'
    assert answer(s, 'getUserRole') == role


def test_a_bad_user_role_is_refused_and_the_role_kept():
    s = versioned('ur5')
    reply = s.handle('setUserRole admin')
    assert reply.answer == "Failed setting user role: 'admin'" and 'programmer, operator' in reply.refusal
    assert answer(s, 'getUserRole') == 'PROGRAMMER'


def test_flight_reports_and_support_files_are_written_to_the_robots_files(tmp_path):
    s = versioned('ur5e', tmp_path)
    first, second = answer(s, 'generate flight report'), answer(s, 'generate flight report controller')
    assert first.startswith('Flight Report generated with id: ') and first != second
    report_id = first.rsplit(' ', 1)[1]
    report = json.loads((tmp_path / 'flightreports' / f'{report_id}.json').read_text())
    assert (report['id'], report['type'], report['robot_model']) == (report_id, 'system', 'UR5')
    reply = s.handle('generate flight report weekly')
    assert reply.answer.startswith('Flight Report generation failed')
    assert 'controller, software, system' in reply.refusal
    done = answer(s, 'generate support file .')
    assert done.startswith('Completed successfully: ur_20')
    with zipfile.ZipFile(tmp_path / done.split(': ', 1)[1]) as archive:
        assert 'flight_report.json' in archive.namelist()
    (tmp_path / 'usb').mkdir()
    assert answer(s, 'generate support file usb').startswith('Completed successfully: ')
    for outside in ('..', '/../..', 'missing'):
        reply = s.handle(f'generate support file {outside}')
        assert reply.answer.startswith('Support file generation failed') and reply.refusal
