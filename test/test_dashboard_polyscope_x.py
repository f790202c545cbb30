"""PolyScope X (10.x): no dashboard server on port 29999, the Robot API instead, and the driver's POLYSCOPE_X dashboard
services over it: state and program actions with the API's status code, `resume`, the state queries and program
files from 10.12.0 (Robot API 3.1.4), "not implemented" for what the API lacks; no services before 10.11.0. The API
alone, then over DDS."""
import json

import pytest
from dashboard_helpers import DashboardServices
from sim_harness import running_sim
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import OperationalMode
from ur_dashboard_msgs.srv import (
    DownloadProgram,
    GetLoadedProgram,
    GetOperationalMode,
    GetPolyScopeVersion,
    GetPrograms,
    GetProgramState,
    GetRobotMode,
    GetSafetyMode,
    IsInRemoteControl,
    Load,
    RawRequest,
    SetOperationalMode,
    UploadProgram,
)

from ur_sim_driver.robot.robot_api import BAD_REQUEST, CONFLICT, NOT_FOUND, OK, RobotApi
from ur_sim_driver.robot.robot_state import POWER_OFF, POWER_ON_TIME, RobotState
from ur_sim_driver.robot.software import SoftwareVersion
from ur_sim_driver.ros.dashboard import NOT_IMPLEMENTED
from ur_sim_driver.ros.dashboard_polyscope_x import QUIT_ANSWER, TOO_OLD, not_implemented_x


def program(name: str, description: str = '') -> str:
    """A PolyScope X program file's content (the parts ur_sim reads)."""
    return json.dumps({'program': {'programInformation': {
        'name': name, 'description': description, 'createdDate': 5_000_000_000, 'lastSavedDate': 7,
        'lastModifiedDate': None, 'programState': 'FINAL'}}})


@pytest.fixture
def api(tmp_path):
    return RobotApi(RobotState(powered_off=True), SoftwareVersion(10, 12, 0), tmp_path)


def test_state_and_program_actions(api):
    assert api.state_action('POWER_ON').status == OK and api.robot.robot_mode != POWER_OFF
    api.robot.update(POWER_ON_TIME)
    assert api.robot_mode().json() == {'mode': 'IDLE'}
    reply = api.state_action('SELF_DESTRUCT')
    assert reply.status == BAD_REQUEST and 'POWER_ON' in reply.json()['message']
    assert api.program_action('resume').status == CONFLICT  # nothing paused
    assert api.program_state().json() == {'state': 'STOPPED'}
    assert api.loaded_program().json() == {'name': 'external_control'}
    assert api.safety_mode().json() == {'mode': 'NORMAL'}
    assert (api.get_control_mode().json(), api.get_operational_mode().json()) == ({'mode': 'REMOTE'},
                                                                                  {'mode': 'AUTOMATIC'})


def test_programs_are_files_of_the_robot(api, tmp_path):
    assert api.programs().json() == {'programs': []}
    assert api.upload(program('pick')).json() == {'programName': 'pick'}
    assert (tmp_path / 'programs' / 'pick.urpx').is_file()
    assert api.upload(program('pick')).status == BAD_REQUEST  # exists already
    assert api.upload(program('pick', 'new'), update=True).status == OK
    assert api.upload(program('place'), update=True).status == NOT_FOUND
    assert api.upload('{"no": "program"}').status == BAD_REQUEST
    assert api.upload(program('../escape')).status == BAD_REQUEST
    [info] = api.programs().json()['programs']
    assert (info['name'], info['description'], info['createdDate']) == ('pick', 'new', 5_000_000_000)
    assert json.loads(api.download('pick').body)['program']['programInformation']['description'] == 'new'
    assert api.download('place').status == NOT_FOUND
    assert api.load('pick').status == OK and api.loaded_program().json() == {'name': 'pick'}
    assert api.load('place').status == NOT_FOUND


def test_queries_need_robot_api_3_1_4(tmp_path):
    assert not RobotApi(RobotState(), SoftwareVersion(10, 11, 2), tmp_path).queries
    assert RobotApi(RobotState(), SoftwareVersion(10, 12, 0), tmp_path).queries


# ---- over DDS ---------------------------------------------------------------------------------------------------
SERVICES = {'power_off': Trigger, 'power_on': Trigger, 'brake_release': Trigger, 'play': Trigger, 'pause': Trigger,
            'resume': Trigger, 'stop': Trigger, 'quit': Trigger, 'connect': Trigger, 'close_popup': Trigger,
            'shutdown': Trigger, 'clear_operational_mode': Trigger, 'get_robot_mode': GetRobotMode,
            'get_safety_mode': GetSafetyMode, 'program_state': GetProgramState, 'get_loaded_program': GetLoadedProgram,
            'load_program': Load, 'is_in_remote_control': IsInRemoteControl, 'get_operational_mode': GetOperationalMode,
            'set_operational_mode': SetOperationalMode, 'get_polyscope_version': GetPolyScopeVersion,
            'raw_request': RawRequest, 'get_programs': GetPrograms, 'upload_program': UploadProgram,
            'update_program': UploadProgram, 'download_program': DownloadProgram}


@pytest.fixture(scope='module', params=[('ur15', '10.12.0'), ('ur30', '10.11.0')], ids=['10.12.0', '10.11.0'])
def robot(request):
    ur_type, version = request.param
    with running_sim(ur_type=ur_type, software_version=version) as h:
        services = DashboardServices(h, SERVICES)
        yield h, services


def test_no_dashboard_server_on_its_port(robot):
    h, _ = robot
    assert h.sim.dashboard_port is None


def test_actions_answer_the_apis_status_and_resume_exists(robot):
    h, s = robot
    r = s.call('power_off')
    assert (r.success, r.message) == (True, ', status_code: 200')
    assert h.sim.robot.robot_mode == POWER_OFF
    r = s.call('play')  # powered off: the robot refuses
    assert not r.success and r.message.endswith(', status_code: 409')
    assert s.call('power_on').success  # acknowledged at once: the client does not wait for the robot mode
    h.wait_sim_time(1.0)
    assert s.call('brake_release').success
    h.wait_sim_time(1.0)
    for name, state in (('play', 'PLAYING'), ('pause', 'PAUSED'), ('resume', 'PLAYING'), ('stop', 'STOPPED')):
        assert s.call(name).success, name
        assert h.sim.robot.program_state == state, name
    assert s.call('play').success
    assert (s.call('quit').success, s.call('quit').message) == (True, QUIT_ANSWER)
    assert s.call('connect').success and s.call('play').success  # quit closed nothing


def test_what_the_robot_api_lacks_is_not_implemented(robot):
    _, s = robot
    for name, command in (('close_popup', 'commandClosePopup'), ('shutdown', 'commandShutdown'),
                          ('clear_operational_mode', 'commandClearOperationalMode')):
        r = s.call(name)
        assert (r.success, r.message) == (False, not_implemented_x(command)), name
    for name in ('get_polyscope_version', 'set_operational_mode'):
        r = s.call(name, **({'operational_mode': OperationalMode(mode='MANUAL')} if name.startswith('set') else {}))
        assert (r.success, r.answer) == (False, NOT_IMPLEMENTED), name
    assert s.call('raw_request', query='robotmode').answer == not_implemented_x('sendAndReceive')


def test_state_queries_from_10_12(robot):
    h, s = robot
    if not h.sim.host.dashboard.robot_api.queries:
        for name in ('get_robot_mode', 'get_safety_mode', 'get_loaded_program', 'get_operational_mode',
                     'get_programs'):
            assert (s.call(name).success, s.call(name).answer) == (False, NOT_IMPLEMENTED), name
        r = s.call('is_in_remote_control')
        assert (r.success, r.answer) == (False, TOO_OLD.format('commandIsInRemoteControl'))
        r = s.call('program_state')  # no minimum in the client library
        assert r.success and r.state.state in ('PLAYING', 'STOPPED', 'PAUSED') and r.program_name == ''
        return
    r = s.call('get_robot_mode')
    assert r.success and r.answer == '{"mode": "RUNNING"}' and r.robot_mode.mode == 7
    r = s.call('get_safety_mode')
    assert r.success and r.safety_mode.mode == 1  # NORMAL
    assert s.call('get_loaded_program').program_name == 'external_control'
    assert s.call('get_operational_mode').operational_mode.mode == 'AUTOMATIC'
    r = s.call('is_in_remote_control')
    assert r.success and r.remote_control and r.answer == ''


def test_program_files_from_10_12(robot, tmp_path):
    h, s = robot
    source = tmp_path / 'mine.urpx'
    source.write_text(program('my upload'))
    if not h.sim.host.dashboard.robot_api.queries:
        for name, fields in (('upload_program', {'file_path': str(source)}),
                             ('download_program', {'program_name': 'x', 'target_path': str(tmp_path / 'x')})):
            assert (s.call(name, **fields).answer, s.call(name, **fields).success) == (NOT_IMPLEMENTED, False)
        return
    r = s.call('upload_program', file_path=str(source))
    assert r.success and r.program_name == 'my upload'
    r = s.call('upload_program', file_path=str(source))
    assert not r.success and 'exists already' in r.answer
    assert s.call('update_program', file_path=str(source)).success
    r = s.call('upload_program', file_path=str(tmp_path / 'missing.urpx'))
    assert (r.success, r.answer) == (False, f'URPX File not found: {tmp_path / "missing.urpx"}')
    [info] = [p for p in s.call('get_programs').programs if p.name == 'my upload']
    assert (info.created_date, info.last_saved_date, info.program_state) == (5_000_000_000 % 2 ** 32, 7, 'FINAL')
    target = tmp_path / 'back.urpx'
    r = s.call('download_program', program_name='my upload', target_path=str(target))
    assert (r.success, r.answer) == (True, f'Downloaded program to {target}')
    assert json.loads(target.read_text()) == json.loads(source.read_text())
    r = s.call('download_program', program_name='', target_path=str(target))
    assert not r.success and r.answer.endswith('Program name is empty.')
    assert not s.call('download_program', program_name='nothing', target_path=str(target)).success
    try:
        r = s.call('load_program', filename='my upload')
        assert (r.success, r.answer) == (True, ', status_code: 200')
        assert s.call('get_loaded_program').program_name == 'my upload'
        r = s.call('load_program', filename='nothing')
        assert not r.success and r.answer.endswith(', status_code: 404')
    finally:
        s.call('load_program', filename='external_control')
        s.call('play')


def test_before_10_11_the_driver_offers_no_dashboard_service():
    with running_sim(ur_type='ur20', software_version='10.10.0') as h:
        [client] = [c for c in h.sim.components if c.name == 'dashboard_client']
        names = [srv.srv_name for srv in client.node.services]
        assert not [n for n in names if n.startswith('/dashboard_client/') and 'parameter' not in n], names
        assert h.sim.dashboard_port is None
