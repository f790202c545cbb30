"""RobotState: every transition and refusal, with explicit simulated times."""
import pytest

from ur_sim_driver.robot.robot_state import (
    BRAKE_RELEASE_TIME,
    EXTERNAL_CONTROL_PROGRAM,
    IDLE,
    NORMAL,
    PAUSED,
    PLAYING,
    POWER_OFF,
    POWER_ON,
    POWER_ON_TIME,
    PROTECTIVE_STOP,
    RUNNING,
    STOPPED,
    UNLOCK_DELAY,
    RobotState,
)


def test_default_start_can_move():
    r = RobotState()
    assert (r.robot_mode, r.safety_mode, r.program_state) == (RUNNING, NORMAL, PLAYING)
    assert r.loaded_program == EXTERNAL_CONTROL_PROGRAM
    assert r.program_running
    assert r.motion_refusal() is None
    s = r.status()
    assert (s.robot_mode, s.safety_mode, s.program_state, s.program_running) == (RUNNING, NORMAL, PLAYING, True)


def test_powered_off_start_names_the_robot_mode():
    r = RobotState(powered_off=True)
    assert (r.robot_mode, r.program_state) == (POWER_OFF, STOPPED)
    assert not r.program_running
    assert 'POWER_OFF' in r.motion_refusal()


def test_power_on_then_brake_release_take_simulated_time():
    r = RobotState(powered_off=True)
    r.update(10.0)
    assert r.power_on() is None
    assert r.robot_mode == POWER_ON
    assert not r.update(10.0 + POWER_ON_TIME - 1e-6)
    assert r.robot_mode == POWER_ON
    assert r.update(10.0 + POWER_ON_TIME)
    assert r.robot_mode == IDLE
    assert r.brake_release() is None
    r.update(10.0 + POWER_ON_TIME + BRAKE_RELEASE_TIME - 1e-6)
    assert r.robot_mode == IDLE
    assert r.update(10.0 + POWER_ON_TIME + BRAKE_RELEASE_TIME)
    assert r.robot_mode == RUNNING
    # RUNNING but the program is stopped: still no motion, and the reason names the program state.
    assert 'STOPPED' in r.motion_refusal()
    assert r.play() is None
    assert r.motion_refusal() is None


def test_brake_release_while_powered_off_powers_on_first():
    r = RobotState(powered_off=True)
    r.update(1.0)
    assert r.brake_release() is None
    assert r.robot_mode == POWER_ON
    r.update(1.0 + POWER_ON_TIME)
    assert r.robot_mode == IDLE
    r.update(1.0 + POWER_ON_TIME + BRAKE_RELEASE_TIME)
    assert r.robot_mode == RUNNING


def test_brake_release_during_power_on_follows_it():
    r = RobotState(powered_off=True)
    r.power_on()
    r.update(0.1)
    r.brake_release()
    r.brake_release()  # a second call does not add another step
    r.update(POWER_ON_TIME)
    assert r.robot_mode == IDLE
    r.update(POWER_ON_TIME + BRAKE_RELEASE_TIME)
    assert r.robot_mode == RUNNING
    assert not r.update(100.0)


def test_power_on_and_brake_release_when_running_change_nothing():
    r = RobotState()
    assert r.power_on() is None
    assert r.brake_release() is None
    assert not r.update(5.0)
    assert r.robot_mode == RUNNING


def test_power_off_stops_program_and_cancels_transitions():
    r = RobotState(powered_off=True)
    r.brake_release()
    r.power_off()
    assert not r.update(10.0)
    assert (r.robot_mode, r.program_state) == (POWER_OFF, STOPPED)
    r2 = RobotState()
    r2.power_off()
    assert (r2.robot_mode, r2.program_state) == (POWER_OFF, STOPPED)
    assert 'POWER_OFF' in r2.motion_refusal()


@pytest.mark.parametrize('mode_setup', ['powered_off', 'idle'])
def test_play_refused_unless_running(mode_setup):
    r = RobotState(powered_off=True)
    if mode_setup == 'idle':
        r.power_on()
        r.update(POWER_ON_TIME)
    reason = r.play()
    assert reason is not None and ('POWER_OFF' in reason or 'IDLE' in reason)
    assert r.program_state == STOPPED


def test_pause_play_stop():
    r = RobotState()
    assert r.pause() is None
    assert r.program_state == PAUSED
    assert 'PAUSED' in r.motion_refusal()
    assert 'PAUSED' in r.pause()  # pausing a paused program is refused
    assert r.play() is None
    assert r.program_state == PLAYING
    assert r.stop() is None
    assert r.program_state == STOPPED
    assert r.stop() is None  # stop is idempotent
    assert 'STOPPED' in r.pause()


def test_load_program_by_name_or_path_and_missing():
    r = RobotState(programs=('wait_program.urp',))
    assert r.programs == (EXTERNAL_CONTROL_PROGRAM, 'wait_program.urp')
    assert r.load_program('wait_program.urp') is None
    assert (r.loaded_program, r.program_state) == ('wait_program.urp', STOPPED)
    assert r.loaded_program_path == '/programs/wait_program.urp'
    assert r.play() is None
    # Another program playing: robot_program_running stays false and motion is refused, naming it.
    assert not r.program_running
    assert 'wait_program.urp is playing' in r.motion_refusal()
    assert r.load_program('/programs/external_control.urp') is None
    assert r.loaded_program == EXTERNAL_CONTROL_PROGRAM
    for missing in ('bogus.urp', '/other/wait_program.urp', 'sub/wait_program.urp', ''):
        reason = r.load_program(missing)
        assert reason is not None and 'does not exist' in reason
    assert r.loaded_program == EXTERNAL_CONTROL_PROGRAM


def test_protective_stop_pauses_and_unlock_waits_five_seconds():
    r = RobotState()
    r.update(20.0)
    r.protective_stop(20.0, 'tool0 touched windshield (120 N)')
    assert (r.safety_mode, r.program_state) == (PROTECTIVE_STOP, PAUSED)
    reason = r.motion_refusal()
    assert 'PROTECTIVE_STOP' in reason and 'windshield' in reason
    r.protective_stop(21.0, 'again')  # a second stop does not move the unlock time
    assert r.stop_time == 20.0
    assert 'NORMAL' in r.play()  # play is refused while stopped
    r.update(20.0 + UNLOCK_DELAY - 0.1)
    assert r.unlock_wait() == pytest.approx(0.1)
    reason = r.unlock_protective_stop()
    assert reason is not None and '0.1 s left' in reason
    assert r.safety_mode == PROTECTIVE_STOP
    r.update(20.0 + UNLOCK_DELAY)
    assert r.unlock_wait() == 0.0
    assert r.unlock_protective_stop() is None
    assert r.safety_mode == NORMAL
    assert 'PAUSED' in r.motion_refusal()  # the program must be resumed
    assert r.play() is None
    assert r.motion_refusal() is None


def test_unlock_without_stop_does_nothing():
    r = RobotState()
    assert r.unlock_wait() == 0.0
    assert r.unlock_protective_stop() is None
    assert r.safety_mode == NORMAL


def test_restart_safety_powers_off():
    r = RobotState()
    r.protective_stop(0.0, 'x')
    assert r.restart_safety() is None
    assert (r.safety_mode, r.robot_mode, r.program_state) == (NORMAL, POWER_OFF, STOPPED)


def test_resend_robot_program_and_hand_back_control():
    r = RobotState()
    r.load_program(EXTERNAL_CONTROL_PROGRAM)
    assert r.hand_back_control() is not None  # not running
    assert r.resend_robot_program() is None
    assert r.program_running
    assert r.hand_back_control() is None
    assert r.program_state == STOPPED
    off = RobotState(powered_off=True)
    assert 'POWER_OFF' in off.resend_robot_program()
