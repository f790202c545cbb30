"""DashboardServer: the robot's dashboard answers (wording of UR's dashboard server) and their effect."""
from ur_sim_driver.robot.dashboard_server import UNLOCK_REFUSED, DashboardServer
from ur_sim_driver.robot.robot_state import (
    BRAKE_RELEASE_TIME,
    POWER_ON_TIME,
    UNLOCK_DELAY,
    RobotState,
)


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
