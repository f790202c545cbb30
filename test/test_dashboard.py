"""`/dashboard_client/*` on a running ur_sim over DDS: every transition, refusals, and the controller_stopper.

Answers are those of the real driver (ur_robot_driver 3.8 over the client library): `message` / `answer` is the
robot's dashboard answer, or "Expected: <pattern>, but received: <answer>" when the robot refused.
"""
import time

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from sim_harness import TIMEOUT, point, running_sim, trajectory, wait_answer, wait_for, wait_still
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import RobotMode, SafetyMode
from ur_dashboard_msgs.srv import (
    AddToLog,
    GetLoadedProgram,
    GetProgramState,
    GetRobotMode,
    GetSafetyMode,
    IsInRemoteControl,
    IsProgramRunning,
    IsProgramSaved,
    Load,
    Popup,
    RawRequest,
)

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import UNLOCK_DELAY
from ur_sim_driver.ros.dashboard import NOT_CONNECTED

ZERO = np.zeros(6)
TRIGGERS = ('power_on', 'power_off', 'brake_release', 'play', 'pause', 'stop', 'unlock_protective_stop',
            'restart_safety', 'close_popup', 'close_safety_popup', 'clear_operational_mode', 'connect', 'quit',
            'shutdown')
TYPED = {'get_robot_mode': GetRobotMode, 'get_safety_mode': GetSafetyMode, 'program_running': IsProgramRunning,
         'program_state': GetProgramState, 'program_saved': IsProgramSaved, 'get_loaded_program': GetLoadedProgram,
         'load_program': Load, 'load_installation': Load, 'is_in_remote_control': IsInRemoteControl,
         'popup': Popup, 'add_to_log': AddToLog, 'raw_request': RawRequest}


class Dashboard:
    """Service clients for every /dashboard_client/* service."""

    def __init__(self, h) -> None:
        self.h = h
        self.clients = {name: h.client.create_client(Trigger, f'/dashboard_client/{name}') for name in TRIGGERS}
        self.clients.update({name: h.client.create_client(t, f'/dashboard_client/{name}') for name, t in TYPED.items()})
        for name, client in self.clients.items():
            wait_still(client.service_is_ready, what=f'/dashboard_client/{name}')

    def call(self, name: str, **fields):
        client = self.clients[name]
        request = (TYPED.get(name) or Trigger).Request(**fields)
        return wait_answer(client.call_async(request), f'the answer of /dashboard_client/{name}')

    def ok(self, name: str, **fields):
        response = self.call(name, **fields)
        text = getattr(response, 'message', None) or getattr(response, 'answer', '')
        assert response.success, f'{name} failed: {text}'
        return response

    def raw(self, query: str) -> str:
        return self.call('raw_request', query=query).answer

    def ready(self) -> None:
        """Bring the robot back to RUNNING / NORMAL / External Control playing, as a user would."""
        self.call('connect')
        self.ok('brake_release')
        with self.h.sim._lock:
            stopped = self.h.sim.robot.unlock_wait()
        if stopped:
            self.h.wait_sim_time(stopped + 0.01)
        self.ok('unlock_protective_stop')
        if self.h.sim.robot.loaded_program != 'external_control.urp':
            self.ok('load_program', filename='external_control.urp')
        self.ok('play')
        wait_for(lambda: self.h.sim.robot.motion_refusal() is None, what='the robot ready to move')


def test_autoconnect_disabled_waits_for_connect():
    """The driver's dashboard client node parameter autoconnect: false starts it disconnected."""
    # Before the module's ur_sim exists: both would share the test process's domain.
    with running_sim(ros_args=['-p', 'dashboard_client:autoconnect:=false']) as h:
        d = Dashboard(h)
        r = d.call('get_robot_mode')
        assert (r.success, r.answer) == (False, NOT_CONNECTED)
        assert d.ok('connect')
        assert d.ok('get_robot_mode').answer == 'Robotmode: RUNNING'


@pytest.fixture(scope='module')
def h():
    with running_sim() as harness:
        yield harness


@pytest.fixture
def d(h):
    dash = Dashboard(h)
    dash.ready()
    return dash


def send_when_active(h, goal):
    """Send `goal` once the controller's interface has heard that the robot can move again.

    The controller_stopper's gate reaches the interface process a little after the robot state changed (the
    real driver's controllers, too, come back a moment after robot_program_running): a goal sent in between is
    still refused, so this sends again until accepted, within the deadline.
    """
    deadline = time.monotonic() + TIMEOUT
    while True:
        handle = h.send(goal)
        if handle.accepted or time.monotonic() > deadline:
            return handle
        h.wait_sim_time(0.01)


def goal_rejected(h, target) -> bool:
    """The goal is refused: rejected by the controller's interface or, when the robot state changed just before
    the interface heard of it, accepted and ended at once with INVALID_GOAL (both as upstream)."""
    handle = h.send(h.goal([point(target, 1.0, ZERO)]))
    if not handle.accepted:
        return True
    status, code, text = h.result(handle)
    return code == rc.INVALID_GOAL and text.startswith('the controller is not running')


def topic_moves_arm(h, target, dt: float = 2.0) -> bool:
    """Whether a 0.3 s topic trajectory moves the arm within `dt` [s] of simulated time (long: in fast mode the
    message may arrive tenths of a simulated second after the publish)."""
    q0 = h.q
    h.topic.publish(trajectory(h.joints, [point(target, 0.3, ZERO)]))
    h.wait_sim_time(dt)
    return float(np.abs(h.q - q0).max()) > 1e-3


# ---- start-up like a real robot (first, before the module's ur_sim starts: one ur_sim at a time) ----
def test_start_powered_off_sequence_then_goal_succeeds(capfd):
    err = []

    def logged(text: str) -> bool:  # the controller's interface process logs to the captured stderr
        err.append(capfd.readouterr().err)
        return any(text in e for e in err)

    with running_sim(start_powered_off=True) as h:
        d = Dashboard(h)
        assert d.ok('get_robot_mode').answer == 'Robotmode: POWER_OFF'
        assert d.ok('program_state').answer == 'STOPPED external_control.urp'
        assert not d.ok('program_running').program_running
        target = h.q + 0.2
        assert goal_rejected(h, target)
        assert not topic_moves_arm(h, target)
        refused = 'the controller is not running: robot mode is POWER_OFF; motion needs RUNNING'
        wait_for(lambda: logged(f'Rejected FollowJointTrajectory goal: {refused}'), what='the goal rejection logged')
        wait_for(lambda: logged(f'Dropped JointTrajectory message: {refused}'), what='the message refusal logged')
        assert d.ok('power_on').message == 'Powering on'
        assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.IDLE
        assert goal_rejected(h, target)
        assert d.ok('brake_release').message == 'Brake releasing'
        assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.RUNNING
        assert goal_rejected(h, target)  # External Control is not playing yet
        assert d.ok('play').message == 'Starting program'
        assert d.ok('program_running').program_running
        wait_for(lambda: h.sim.robot.motion_refusal() is None, TIMEOUT, 'motion allowed')
        handle = send_when_active(h, h.goal([point(target, 1.0, ZERO)]))
        assert handle.accepted
        assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
        assert np.abs(h.q - target).max() < 0.01


def test_protective_stop_unlock_after_five_seconds_and_play():
    # In real time: the 5 s window must not pass while the test is still checking the stop (fast mode might).
    with running_sim(real_time_factor=1.0) as h:
        d = Dashboard(h)
        log = h.rosout()
        handle = h.send(h.goal([point(h.q + 0.5, 4.0, ZERO)]))
        h.wait_sim_time(0.3)
        with h.sim._lock:
            t_stop = h.sim.sim.time
            h.sim.robot.protective_stop(t_stop, 'test contact: tool0 with windshield, 150 N')
        status, code, text = h.result(handle)
        assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL)
        assert text == 'Current goal cancelled during deactivate transition.'
        wait_still(lambda: any('PROTECTIVE_STOP' in m and 'windshield' in m for _, m in log), what='the cause')
        assert d.ok('get_safety_mode').safety_mode.mode == SafetyMode.PROTECTIVE_STOP
        assert d.ok('program_state').state.state == 'PAUSED'
        assert goal_rejected(h, h.q + 0.1)
        r = d.call('unlock_protective_stop')
        assert not r.success
        assert r.message == ('Expected: Protective stop releasing, but received: Cannot unlock protective stop '
                             'until 5s after occurrence. Always inspect cause of protective stop before unlocking')
        assert h.sim.sim.time < t_stop + UNLOCK_DELAY  # the refusal came within the 5 s
        # The robot's clock (advanced at the start of each cycle) is the one that counts for the 5 s.
        wait_for(lambda: h.sim.robot.unlock_wait() == 0.0, what='5 s of simulated time after the stop')
        assert h.sim.sim.time >= t_stop + UNLOCK_DELAY
        assert d.ok('unlock_protective_stop').message == 'Protective stop releasing'
        assert d.ok('get_safety_mode').safety_mode.mode == SafetyMode.NORMAL
        assert goal_rejected(h, h.q + 0.1)  # the program is still paused
        assert d.ok('play').message == 'Starting program'
        wait_for(lambda: h.sim.robot.motion_refusal() is None, what='motion allowed again')
        handle = send_when_active(h, h.goal([point(h.q + 0.1, 0.5, ZERO)]))
        assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)


# ---- queries and fixed answers -----------------------------------------------------------------------
def test_queries_answer_as_the_robot(d):
    r = d.ok('get_robot_mode')
    assert (r.answer, r.robot_mode.mode) == ('Robotmode: RUNNING', RobotMode.RUNNING)
    r = d.ok('get_safety_mode')
    assert (r.answer, r.safety_mode.mode) == ('Safetymode: NORMAL', SafetyMode.NORMAL)
    r = d.ok('program_state')
    assert (r.answer, r.state.state, r.program_name) == ('PLAYING external_control.urp', 'PLAYING',
                                                         'external_control.urp')
    r = d.ok('program_running')
    assert (r.answer, r.program_running) == ('Program running: true', True)
    r = d.ok('get_loaded_program')
    assert (r.answer, r.program_name) == ('Loaded program: /programs/external_control.urp',
                                          '/programs/external_control.urp')
    r = d.ok('program_saved')
    assert (r.answer, r.program_saved, r.program_name) == ('true external_control.urp', True, 'external_control.urp')
    r = d.ok('is_in_remote_control')
    assert (r.remote_control, r.answer) == (True, '')  # the driver leaves `answer` empty here
    assert d.ok('popup', message='Glue gun warming up').answer == 'showing popup'
    assert d.ok('close_popup').message == 'closing popup'
    assert d.ok('close_safety_popup').message == 'closing safety popup'
    assert d.ok('add_to_log', message='bead 1 done').answer == 'Added log message'
    r = d.call('add_to_log', message='')
    assert not r.success and r.answer == 'Expected: Added log message, but received: No log message to add'
    assert d.ok('clear_operational_mode').message.startswith('No longer controlling the operational mode.')
    r = d.ok('load_installation', filename='default.installation')
    assert r.answer == 'Loading installation: /programs/default.installation'
    r = d.call('load_installation', filename='missing.installation')
    assert not r.success and r.answer.endswith('but received: File not found: missing.installation')


def test_raw_request_answers_what_the_state_machine_knows(d):
    assert d.raw('robotmode') == 'Robotmode: RUNNING'
    assert d.raw('safetymode') == 'Safetymode: NORMAL'
    assert d.raw('running') == 'Program running: true'
    assert d.raw('programState') == 'PLAYING external_control.urp'
    assert d.raw('get loaded program') == 'Loaded program: /programs/external_control.urp'
    assert d.raw('is in remote control') == 'true'
    assert d.raw('set_payload(2.0)') == "could not understand: 'set_payload(2.0)'"
    # Commands sent raw act as well.
    assert d.raw('pause') == 'Pausing program'
    wait_for(lambda: d.h.sim.robot.program_state == 'PAUSED', what='the raw pause')
    assert d.raw('play') == 'Starting program'


def test_quit_disconnects_until_connect(d):
    assert d.ok('quit').message == 'Disconnected'
    r = d.call('get_robot_mode')
    assert (r.success, r.answer) == (False, NOT_CONNECTED)
    r = d.call('play')
    assert (r.success, r.message) == (False, NOT_CONNECTED)
    assert d.raw('robotmode') == NOT_CONNECTED
    assert d.ok('connect')
    assert not d.call('connect').success  # connected already: the client library refuses
    assert d.ok('get_robot_mode').answer == 'Robotmode: RUNNING'


# ---- the driver's own dashboard scenario (client library run_program / program_interaction) -------------
def test_driver_program_scenario(d):
    assert d.ok('power_off').message == 'Powering off'
    assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.POWER_OFF
    assert d.ok('power_on').message == 'Powering on'
    # The service returns once the robot is powered (the driver waits for IDLE).
    assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.IDLE
    assert d.ok('brake_release').message == 'Brake releasing'
    assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.RUNNING
    r = d.ok('load_program', filename='wait_program.urp')
    assert r.answer == 'Loading program: /programs/wait_program.urp'
    r = d.ok('program_state')
    assert (r.state.state, r.program_name) == ('STOPPED', 'wait_program.urp')
    assert d.ok('play').message == 'Starting program'
    r = d.ok('program_state')
    assert (r.state.state, r.program_name) == ('PLAYING', 'wait_program.urp')
    assert d.ok('program_running').program_running
    # wait_program plays, not External Control: robot_program_running is false, so motion is refused.
    assert 'wait_program.urp is playing' in d.h.sim.robot.motion_refusal()
    assert d.ok('pause').message == 'Pausing program'
    assert d.ok('program_state').state.state == 'PAUSED'
    assert d.ok('play').message == 'Starting program'
    assert d.ok('program_state').state.state == 'PLAYING'
    assert d.ok('stop').message == 'Stopped'
    r = d.ok('program_state')
    assert (r.state.state, r.program_name) == ('STOPPED', 'wait_program.urp')
    assert not d.ok('program_running').program_running
    r = d.call('load_program', filename='bogus.urp')
    assert not r.success
    assert r.answer == 'Expected: Loading program: .*bogus\\.urp.*, but received: File not found: bogus.urp'
    assert d.ok('get_loaded_program').program_name == '/programs/wait_program.urp'
    assert d.ok('power_off').message == 'Powering off'


# ---- refusals --------------------------------------------------------------------------------------------
def test_play_while_powered_off_is_refused_and_brake_release_powers_on(d):
    d.ok('power_off')
    r = d.call('play')
    assert (r.success, r.message) == (False, 'Expected: Starting program, but received: Failed to execute: play')
    r = d.call('pause')
    assert (r.success, r.message) == (False, 'Expected: Pausing program, but received: Failed to execute: pause')
    # As on the real robot (and the driver's documentation): brake release from POWER_OFF powers on first.
    assert d.ok('brake_release').message == 'Brake releasing'
    assert d.ok('get_robot_mode').answer == 'Robotmode: RUNNING'
    assert d.ok('play').message == 'Starting program'


def test_goals_and_topic_refused_while_powered_off_and_paused(d):
    h = d.h
    for command, state in (('power_off', 'POWER_OFF'), ('pause', 'PAUSED')):
        d.ok('power_on')  # no-op when running
        d.ok('brake_release')
        d.ok('play')
        d.ok(command)
        wait_for(lambda: h.sim._refusal is not None, what='the controller_stopper')
        target = h.q + 0.2
        assert goal_rejected(h, target), state
        assert not topic_moves_arm(h, target), state
    d.ready()
    handle = send_when_active(h, h.goal([point(h.q + 0.1, 0.5, ZERO)]))
    assert handle.accepted
    assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)


@pytest.mark.parametrize('command, state', [('pause', 'PAUSED'), ('power_off', 'POWER_OFF'), ('stop', 'STOPPED')])
def test_controller_stopper_ends_active_goal_and_holds(d, command, state):
    h = d.h
    start = h.q
    handle = send_when_active(h, h.goal([point(start + 0.6, 4.0, ZERO)]))
    assert handle.accepted
    h.wait_sim_time(0.5)
    log = h.rosout()
    d.ok(command)
    status, code, text = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL)
    assert text == 'Current goal cancelled during deactivate transition.'  # upstream's on_deactivate
    wait_still(lambda: any(m.startswith('the controller was deactivated: ') and state in m for _, m in log),
               what='the reason in the log')
    q_stop = h.q
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q_stop).max() < 0.02  # held where it stopped (plus braking), not at the target
    assert np.abs(h.q - (start + 0.6)).max() > 0.2
    assert np.abs(h.sim.sim.state().qd).max() < 0.01


def test_restart_safety_and_shutdown(d):
    assert d.ok('restart_safety').message == 'Restarting safety'
    assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.POWER_OFF
    assert d.ok('shutdown').message == 'Shutting down'
    assert d.call('get_robot_mode').answer == NOT_CONNECTED
    d.ok('connect')
    assert d.ok('get_robot_mode').robot_mode.mode == RobotMode.POWER_OFF
