"""io_and_status_controller, ur_configuration_controller and /ur_sim/set_input over real DDS.

IO round trips (the driver's own IO test among them), every refusal, the latched robot status topics for a
late subscriber and their changes, resend_robot_program / hand_back_control, the speed slider on the speed
scaling topic and on a trajectory's duration, the software version per robot type; and the pure payload check.
"""
from __future__ import annotations

import threading

import numpy as np
import pytest
from geometry_msgs.msg import Vector3
from sim_harness import point, running_sim, wait_answer, wait_for, wait_still
from std_msgs.msg import Bool, Float64
from std_srvs.srv import Trigger
from test_payload import pinocchio_gravity
from ur_dashboard_msgs.msg import RobotMode, SafetyMode
from ur_msgs.msg import Analog, IOStates, ToolDataMsg
from ur_msgs.srv import GetRobotSoftwareVersion, SetAnalogOutput, SetIO, SetPayload, SetSpeedSliderFraction

from ur_sim_driver.controllers.io_and_status import payload_refusal
from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.robot_state import IDLE, NORMAL, POWER_OFF, POWER_ON, PROTECTIVE_STOP, RUNNING

IO = '/io_and_status_controller'


class Latest:
    """Thread-safe record of the messages of one topic: all of them, with the simulated time of arrival."""

    def __init__(self, h) -> None:
        self._h = h
        self._lock = threading.Lock()
        self.items: list = []

    def __call__(self, msg) -> None:
        with self._lock:
            self.items.append((msg, self._h.sim.sim.time))

    @property
    def last(self):
        with self._lock:
            return self.items[-1][0] if self.items else None

    def first(self, condition):
        """(message, simulated time of arrival) of the first message satisfying `condition`, or None."""
        with self._lock:
            return next(((m, t) for m, t in self.items if condition(m)), None)


def client_for(h, srv_type, name: str):
    """One client per service for the harness's lifetime (destroying one under the spinning executor races)."""
    clients = h.__dict__.setdefault('_test_clients', {})
    if name not in clients:
        clients[name] = h.client.create_client(srv_type, name)
        wait_still(clients[name].service_is_ready, what=f'the service {name}')
    return clients[name]


def call(h, srv_type, name: str, request, timeout: float = 10.0):
    return wait_answer(client_for(h, srv_type, name).call_async(request), f'the answer of {name}', timeout)


def set_io(h, fun: int, pin: int, state: float) -> bool:
    return call(h, SetIO, f'{IO}/set_io', SetIO.Request(fun=fun, pin=pin, state=float(state))).success


def set_input(h, fun: int, pin: int, state: float) -> bool:
    return call(h, SetIO, '/ur_sim/set_input', SetIO.Request(fun=fun, pin=pin, state=float(state))).success


def slider(h, fraction: float) -> bool:
    return call(h, SetSpeedSliderFraction, f'{IO}/set_speed_slider',
                SetSpeedSliderFraction.Request(speed_slider_fraction=fraction)).success


def trigger(h, name: str) -> Trigger.Response:
    return call(h, Trigger, f'{IO}/{name}', Trigger.Request())


def version(h) -> GetRobotSoftwareVersion.Response:
    return call(h, GetRobotSoftwareVersion, '/ur_configuration_controller/get_robot_software_version',
                GetRobotSoftwareVersion.Request())


# ---- pure -----------------------------------------------------------------------------------------------
def test_payload_refusals_name_field_value_and_limit():
    cog, inertia = np.array([0.0, 0.0, 0.1]), np.array([0.01, 0.01, 0.02, 0.0, 0.0, 0.0])
    assert payload_refusal('ur5e', 5.0, cog, inertia, 0.0) is None
    assert payload_refusal('ur10e', 12.5, cog, np.zeros(6), 1.0) is None
    assert '[0, 5.0] kg' in payload_refusal('ur5e', 5.1, cog, inertia, 0.0)
    assert '[0, 10.0] kg' in payload_refusal('ur10', 10.5, cog, inertia, 0.0)
    assert 'mass = -1.0 kg' in payload_refusal('ur5', -1.0, cog, inertia, 0.0)
    assert 'center_of_gravity.y = nan' in payload_refusal('ur5', 1.0, np.array([0.0, np.nan, 0.0]), inertia, 0.0)
    assert 'izz = -0.1' in payload_refusal('ur5', 1.0, cog, np.array([0.0, 0.0, -0.1, 0, 0, 0]), 0.0)
    assert 'transition_time = -1.0 s' in payload_refusal('ur5', 1.0, cog, inertia, -1.0)


# ---- over DDS ---------------------------------------------------------------------------------------------
def test_io_round_trips_refusals_inputs_and_cb3_version():
    # Real time at the CB3 rate (125 Hz): one control cycle is 8 ms of wall time, far above DDS latency.
    with running_sim(ur_type='ur5', real_time_factor=1.0) as h:
        dt = h.sim.sim.control_dt
        io, tool = Latest(h), Latest(h)
        h.listen(IOStates, f'{IO}/io_states', io)
        h.listen(ToolDataMsg, f'{IO}/tool_data', tool)
        wait_for(lambda: io.last is not None and tool.last is not None, what='io_states and tool_data')
        first = io.last
        assert [d.pin for d in first.digital_out_states] == list(range(18))
        assert [d.pin for d in first.digital_in_states] == list(range(18))
        assert len(first.analog_in_states) == len(first.analog_out_states) == 2 and first.flag_states == []

        # set_io, then io_states shows it within one control cycle of the answer.
        answered = []
        request = SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=5, state=1.0)
        future = client_for(h, SetIO, f'{IO}/set_io').call_async(request)
        future.add_done_callback(lambda _: answered.append(h.sim.sim.time))
        wait_for(lambda: answered, what='the set_io answer')
        assert future.result().success
        wait_for(lambda: io.first(lambda m: m.digital_out_states[5].state), what='digital output 5 on')
        _, t_seen = io.first(lambda m: m.digital_out_states[5].state)
        assert t_seen <= answered[0] + dt + 1e-9, (t_seen - answered[0]) / dt

        # The driver's IO test: pin 0 on, then off, followed by io_states.
        assert set_io(h, 1, 0, 1.0)
        wait_for(lambda: io.last.digital_out_states[0].state, 5.0, 'digital output 0 on')
        assert set_io(h, 1, 0, 0.0)
        wait_for(lambda: not io.last.digital_out_states[0].state, 5.0, 'digital output 0 off')
        assert io.last.digital_out_states[5].state  # the other output kept its state

        # Tool output 17, analog output (fraction of the span, domain kept / set), tool voltage.
        assert set_io(h, 1, 17, 1.0)
        assert set_io(h, 3, 1, 0.25)
        assert set_io(h, 4, 0, 24.0)
        wait_for(lambda: io.last.digital_out_states[17].state and io.last.analog_out_states[1].state > 0.0,
                 what='tool output 17 and analog output 1')
        assert io.last.analog_out_states[1].state == pytest.approx(2.5)  # a quarter of 0-10 V
        assert io.last.analog_out_states[1].domain == Analog.VOLTAGE
        wait_for(lambda: tool.last.tool_output_voltage == 24, what='tool voltage 24 V')
        assert tool.last.tool_mode == ToolDataMsg.TOOL_RUNNING_MODE
        assert call(h, SetAnalogOutput, f'{IO}/set_analog_output',
                    SetAnalogOutput.Request(data=Analog(pin=0, domain=Analog.CURRENT, state=0.5))).success
        wait_for(lambda: io.last.analog_out_states[0].domain == Analog.CURRENT, what='analog output 0 in current')
        assert io.last.analog_out_states[0].state == pytest.approx(0.012)  # 4 mA + half of 16 mA

        # Every refusal answers false and changes nothing.
        before = h.sim.sim.io
        refused = {
            'digital pin 18': set_io(h, 1, 18, 1.0),
            'digital pin -1': set_io(h, 1, -1, 1.0),
            'flags (fun 2)': set_io(h, 2, 0, 1.0),
            'fun 0': set_io(h, 0, 0, 1.0),
            'fun 5': set_io(h, 5, 0, 1.0),
            'analog pin 2': set_io(h, 3, 2, 0.5),
            'analog 1.5': set_io(h, 3, 0, 1.5),
            'tool voltage 5': set_io(h, 4, 0, 5.0),
            'tool voltage 48': set_io(h, 4, 0, 48.0),
            'slider 0': slider(h, 0.0),
            'slider 0.005': slider(h, 0.005),
            'slider 1.01': slider(h, 1.01),
            'analog domain 2': call(h, SetAnalogOutput, f'{IO}/set_analog_output', SetAnalogOutput.Request(
                data=Analog(pin=0, domain=2, state=0.5))).success,
            'input pin 18': set_input(h, 1, 18, 1.0),
            'input fun 4': set_input(h, 4, 0, 1.0),
            'analog input 11 V': set_input(h, 3, 0, 11.0),
            'analog input pin 4': set_input(h, 3, 4, 1.0),
        }
        assert not any(refused.values()), [k for k, ok in refused.items() if ok]
        assert h.sim.sim.io == before

        # Simulation-only inputs: digital, standard analog, tool analog (with its range).
        assert set_input(h, 1, 9, 1.0)
        assert set_input(h, 3, 1, 7.5)
        assert call(h, SetAnalogOutput, '/ur_sim/set_analog_input',
                    SetAnalogOutput.Request(data=Analog(pin=3, domain=Analog.CURRENT, state=0.01))).success
        wait_for(lambda: io.last.digital_in_states[9].state and io.last.analog_in_states[1].state > 0.0,
                 what='inputs in io_states')
        assert sum(d.state for d in io.last.digital_in_states) == 1
        assert io.last.analog_in_states[1].state == pytest.approx(7.5)
        wait_for(lambda: tool.last.analog_input3 > 0.0, what='tool analog input 3')
        assert tool.last.analog_input3 == pytest.approx(0.01)
        assert tool.last.analog_input_range3 == ToolDataMsg.ANALOG_INPUT_RANGE_CURRENT

        v = version(h)
        assert (v.major, v.minor) == (3, 15)


def test_latched_status_for_a_late_subscriber_and_its_changes():
    with running_sim() as h:
        h.wait_sim_time(0.1)  # the first status went out long before anyone listens
        mode, safety, running = Latest(h), Latest(h), Latest(h)
        h.listen(RobotMode, f'{IO}/robot_mode', mode, latched=True)
        h.listen(SafetyMode, f'{IO}/safety_mode', safety, latched=True)
        h.listen(Bool, f'{IO}/robot_program_running', running, latched=True)
        wait_for(lambda: None not in (mode.last, safety.last, running.last), what='the latched status')
        assert (mode.last.mode, safety.last.mode, running.last.data) == (RUNNING, NORMAL, True)
        # Published on change only: time passing adds nothing.
        h.wait_sim_time(0.05)
        assert len(mode.items) == len(safety.items) == len(running.items) == 1

        robot, lock = h.sim.host.robot, h.sim.host.lock
        assert trigger(h, 'hand_back_control').success
        wait_for(lambda: running.last.data is False, what='robot_program_running false after hand_back_control')
        again = trigger(h, 'hand_back_control')
        assert not again.success and 'robot_program_running is false' in again.message
        assert trigger(h, 'resend_robot_program').success
        wait_for(lambda: running.last.data is True, what='robot_program_running true after resend')

        with lock:
            robot.power_off()
        wait_for(lambda: mode.last.mode == POWER_OFF and running.last.data is False, what='powered off')
        refused = trigger(h, 'resend_robot_program')
        assert not refused.success and 'POWER_OFF' in refused.message
        with lock:
            robot.power_on()
        wait_for(lambda: mode.last.mode == IDLE, what='IDLE after power on')
        with lock:
            robot.brake_release()
        wait_for(lambda: mode.last.mode == RUNNING, what='RUNNING after brake release')
        assert running.last.data is False
        assert trigger(h, 'resend_robot_program').success
        wait_for(lambda: running.last.data is True, what='program running after resend')

        with lock:
            robot.protective_stop(h.sim.sim.time, 'test contact')
        wait_for(lambda: safety.last.mode == PROTECTIVE_STOP, what='PROTECTIVE_STOP')
        wait_for(lambda: running.last.data is False, what='program paused by the stop')
        assert [m.mode for m, _ in mode.items] == [RUNNING, POWER_OFF, POWER_ON, IDLE, RUNNING]
        assert [m.mode for m, _ in safety.items] == [NORMAL, PROTECTIVE_STOP]

        v = version(h)
        assert (v.major, v.minor, v.bugfix) == (5, 25, 1)  # the UR5e's default


def test_speed_slider_scales_the_reported_factor_and_slows_a_trajectory():
    with running_sim() as h:
        scaling = Latest(h)
        h.listen(Float64, '/speed_scaling_state_broadcaster/speed_scaling', scaling)
        wait_for(lambda: scaling.last is not None, what='speed_scaling')

        def move(delta: float, seconds: float) -> float:
            """Move joint 0 by `delta` [rad] in `seconds`; the motion's duration [s] measured in joint states."""
            start = h.q.copy()
            goal = start.copy()
            goal[0] += delta
            rec = h.record()
            handle = h.send(h.goal([point(goal, seconds)]))
            assert handle.accepted
            status, code, message = h.result(handle)
            assert code == rc.SUCCESSFUL, message
            h.wait_sim_time(0.5)  # success comes within the goal tolerance: the arm settles on after it
            h.stop_recording()
            t, q, _ = rec.arrays()
            moving = np.flatnonzero(np.abs(q[:, 0] - start[0]) > 1e-3)
            arrived = np.flatnonzero(np.abs(q[:, 0] - goal[0]) < 1e-3)
            return float(t[arrived[0]] - t[moving[0]])

        full = move(0.3, 1.0)
        assert scaling.last.data == pytest.approx(100.0)
        assert slider(h, 0.5)
        wait_for(lambda: scaling.last.data == pytest.approx(50.0), what='speed scaling 50 %')
        half = move(-0.3, 1.0)
        assert half / full == pytest.approx(2.0, rel=0.08), (full, half)
        assert slider(h, 1.0)
        wait_for(lambda: scaling.last.data == pytest.approx(100.0), what='speed scaling 100 %')


def test_set_payload_over_dds_changes_the_robots_belief_and_so_the_wrench_not_the_efforts():
    # The driver's payload test calls set_payload several times in a row: every one succeeds.
    pose = [0.4, -1.1, 1.2, -0.6, 1.0, 0.3]
    load = dict(mass=3.0, cog=np.array([0.02, -0.03, 0.08]), inertia=np.array([0.012, 0.015, 0.009, 0.0, 0.0, 0.0]))
    with running_sim(ur_type='ur10e', initial_positions=pose) as h:
        def payload(mass, cog=(0.0, 0.0, 0.1), inertia=(0.01, 0.01, 0.02, 0.0, 0.0, 0.0)):
            req = SetPayload.Request(mass=float(mass), center_of_gravity=Vector3(x=cog[0], y=cog[1], z=cog[2]),
                                     ixx=inertia[0], iyy=inertia[1], izz=inertia[2], ixy=inertia[3],
                                     ixz=inertia[4], iyz=inertia[5])
            return call(h, SetPayload, f'{IO}/set_payload', req).success

        assert not payload(12.6)  # above the UR10e's 12.5 kg
        assert not payload(-0.5)
        assert not payload(1.0, inertia=(0.01, -0.01, 0.02, 0.0, 0.0, 0.0))
        assert not payload(1.0, inertia=(0.01, 0.01, 0.5, 0.0, 0.0, 0.0))  # no rigid body has it
        for mass in (1.0, 2.0, 0.0):
            assert payload(mass)

        def at_rest():
            h.wait_sim_time(1.0)
            rec = h.record()
            h.wait_sim_time(0.1)
            h.stop_recording()
            return np.array(rec.effort[-1])

        before = at_rest()
        zero = trigger(h, 'zero_ftsensor')
        assert zero.success, zero.message
        assert payload(load['mass'], load['cog'], load['inertia'])
        after = at_rest()
        # A belief mounts nothing: the arm holds the same load with the same efforts.
        np.testing.assert_allclose(after, before, atol=1e-6 * np.abs(before).max())
        assert np.abs(pinocchio_gravity(h.sim.sim.urdf, pose, load) - pinocchio_gravity(h.sim.sim.urdf, pose)).max() \
            > 1.0  # what a mounted 3 kg would have added
        # zeroed before: the reading is now compensated for 3 kg that are not there, and shows minus their weight
        with h.sim.host.lock:
            wrench = h.sim.sim.wrench()
        assert np.linalg.norm(wrench[:3]) == pytest.approx(3.0 * 9.81, rel=0.01)
