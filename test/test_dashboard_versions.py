"""The dashboard services a robot's software version offers, over DDS: an e-series (PolyScope 5.12.6), a CB3
(3.15.8) and an older e-series (5.5.0), each with the commands its version knows and the client library's refusal
for the others; PolyScope X's program services answer "not implemented" on both series, as the driver's do."""
import zipfile

import pytest
from dashboard_helpers import DashboardServices
from sim_harness import running_sim
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import OperationalMode, SafetyStatus, UserRole
from ur_dashboard_msgs.srv import (
    DownloadProgram,
    GenerateFlightReport,
    GenerateSupportFile,
    GetOperationalMode,
    GetPolyScopeVersion,
    GetPrograms,
    GetRobotModel,
    GetSafetyStatus,
    GetSerialNumber,
    GetUserRole,
    IsInRemoteControl,
    SetOperationalMode,
    SetUserRole,
    UploadProgram,
)

from ur_sim_driver.ros.dashboard import NOT_IMPLEMENTED

SERVICES = {'get_serial_number': GetSerialNumber, 'get_polyscope_version': GetPolyScopeVersion,
            'get_robot_model': GetRobotModel, 'get_safety_status': GetSafetyStatus, 'get_user_role': GetUserRole,
            'set_user_role': SetUserRole, 'get_operational_mode': GetOperationalMode,
            'set_operational_mode': SetOperationalMode, 'generate_flight_report': GenerateFlightReport,
            'generate_support_file': GenerateSupportFile, 'get_programs': GetPrograms,
            'upload_program': UploadProgram, 'update_program': UploadProgram, 'download_program': DownloadProgram,
            'is_in_remote_control': IsInRemoteControl, 'clear_operational_mode': Trigger}


def mismatch(command: str, required: str, actual: str) -> str:
    return (f"Dashboard command '{command}' is not supported by this robot version.(Required version: {required}, "
            f'actual version: {actual})')


@pytest.fixture(scope='module', params=[('ur5e', ''), ('ur10', ''), ('ur5e', '5.5.0')],
                ids=['5.12.6', '3.15.8', '5.5.0'])
def robot(request):
    ur_type, version = request.param
    with running_sim(ur_type=ur_type, software_version=version) as h:
        services = DashboardServices(h, SERVICES)
        yield h, services, h.sim.cfg.software_version


def test_the_version_and_model_are_the_robots(robot):
    h, s, version = robot
    r = s.call('get_polyscope_version')
    assert r.success and r.answer == f'URSoftware {version.dotted()} (simulated)'
    assert (r.version.major, r.version.minor, r.version.bugfix, r.version.build) == tuple(version)
    r = s.call('get_robot_model')
    if version.major == 5 and version.minor < 6:
        assert not r.success and r.answer == mismatch('get robot model', '5.6.0-0', str(version))
    else:
        assert r.success and r.robot_model == 'UR' + h.sim.cfg.ur_type[2:].removesuffix('e').upper()


def test_the_serial_number_from_56_on_e_series_and_312_on_cb3(robot):
    _, s, version = robot
    r = s.call('get_serial_number')
    if version.major == 5 and version.minor < 6:
        assert not r.success and r.serial_number == 0
        assert r.answer == mismatch('get serial number', '5.6.0-0', str(version))
    else:
        assert r.success and r.serial_number > 0 and r.answer.startswith('20')


def test_operational_mode_safety_status_and_remote_control_on_e_series_only(robot):
    _, s, version = robot
    if not version.e_series:
        for name, command, minimum in (('get_operational_mode', 'get operational mode', '5.6.0-0'),
                                       ('get_safety_status', 'safetystatus', '5.4.0-0'),
                                       ('is_in_remote_control', 'is in remote control', '5.6.0-0')):
            r = s.call(name)
            assert not r.success and r.answer == mismatch(command, minimum, str(version)), name
        r = s.call('set_operational_mode', operational_mode=OperationalMode(mode='MANUAL'))
        assert not r.success and r.answer == mismatch('set operational mode', '3.99.0-0', str(version))
        r = s.call('clear_operational_mode')
        assert not r.success and r.message == mismatch('clear operational mode', '5.0.0-0', str(version))
        return
    r = s.call('get_safety_status')
    assert r.success and (r.answer, r.safety_status.status) == ('Safetystatus: NORMAL', SafetyStatus.NORMAL)
    if version.minor < 6:
        assert s.call('get_operational_mode').answer == mismatch('get operational mode', '5.6.0-0', str(version))
        return
    try:
        for mode in (OperationalMode.MANUAL, OperationalMode.AUTOMATIC):
            r = s.call('set_operational_mode', operational_mode=OperationalMode(mode=mode))
            assert r.success and r.answer == f"Operational mode '{mode}' is set"
            r = s.call('get_operational_mode')
            assert r.success and r.operational_mode.mode == mode
        r = s.call('set_operational_mode', operational_mode=OperationalMode(mode='SIDEWAYS'))
        assert not r.success and r.answer.endswith("but received: Failed setting operational mode: 'SIDEWAYS'")
        assert s.call('clear_operational_mode').success
        assert s.call('is_in_remote_control').remote_control
    finally:
        s.call('set_operational_mode', operational_mode=OperationalMode(mode=OperationalMode.AUTOMATIC))


def test_user_roles_on_cb3_only(robot):
    _, s, version = robot
    if version.e_series:
        r = s.call('set_user_role', user_role=UserRole(role=UserRole.OPERATOR))
        assert not r.success and r.answer == mismatch('setUserRole', '5.99.0-0', str(version))
        assert s.call('get_user_role').answer == mismatch('getUserRole', '5.99.0-0', str(version))
        return
    try:
        for role in (UserRole.PROGRAMMER, UserRole.OPERATOR, UserRole.NONE, UserRole.LOCKED, UserRole.RESTRICTED):
            r = s.call('set_user_role', user_role=UserRole(role=role))
            assert r.success and r.answer == f'Setting user role: {role}'
            r = s.call('get_user_role')
            assert r.success and r.user_role.role == role
    finally:
        s.call('set_user_role', user_role=UserRole(role=UserRole.PROGRAMMER))


def test_flight_report_and_support_file_land_in_the_robots_files(robot):
    h, s, version = robot
    if version.e_series and version.minor < 8:
        r = s.call('generate_flight_report')
        assert not r.success and r.answer == mismatch('generate flight report', '5.8.0-0', str(version))
        return
    r = s.call('generate_flight_report')  # report_type SYSTEM, the default
    assert r.success and r.report_id and (h.sim.host.robot_files / 'flightreports' / f'{r.report_id}.json').is_file()
    r = s.call('generate_support_file')  # dir_path '.', the default
    assert r.success and r.generated_file_name.endswith('.zip')
    with zipfile.ZipFile(h.sim.host.robot_files / r.generated_file_name) as archive:
        assert 'flight_report.json' in archive.namelist()
    r = s.call('generate_support_file', dir_path='../outside')
    assert not r.success and 'Support file generation failed' in r.answer


def test_polyscope_x_program_services_are_not_implemented_here(robot):
    _, s, _ = robot
    for name, fields in (('get_programs', {}), ('upload_program', {'file_path': '/tmp/x.urpx'}),
                         ('update_program', {'file_path': '/tmp/x.urpx'}),
                         ('download_program', {'program_name': 'x', 'target_path': '/tmp/x.urpx'})):
        r = s.call(name, **fields)
        assert (r.success, r.answer) == (False, NOT_IMPLEMENTED), name
