"""The primary and secondary interfaces on their TCP ports, read with a decoder of our own written from the Client
Library's field lists: the version message first, the robot state every 100 ms of simulated time, URScript from a
client run on the robot with its key, runtime exception and text messages, controller commands, a client that never
reads, and input that closes the connection.

The port is stepped where the node steps it: after every control cycle (``PrimaryPort.tick`` wrapped around the
lockstep simulation's ``step_once``)."""
from __future__ import annotations

import math
import socket
import struct
import threading

import numpy as np
import pytest
from port_helpers import recv_exactly
from scipy.spatial.transform import Rotation
from sim_harness import running_sim, wait_for, wait_still

from ur_sim_driver.ports import primary_messages as pm
from ur_sim_driver.ports.primary_port import MAX_SCRIPT, PrimaryPort
from ur_sim_driver.robot.motor_currents import motor_currents
from ur_sim_driver.robot.robot_state import POWER_OFF, POWER_ON, RUNNING, STOPPED
from ur_sim_driver.robot.software import SoftwareVersion

pytestmark = pytest.mark.timeout(120)  # sockets answer at once and the simulation steps only in the waits

TIMEOUT = 10.0  # [s] of wall time for a package: it is queued before the test reads it
STATE, MESSAGE = 16, 20
TEXT, VERSION, KEY, RUNTIME_EXCEPTION = 0, 3, 7, 10
ROBOT_MODE, JOINT, TOOL, MASTERBOARD, CARTESIAN, KINEMATICS, CONFIGURATION = 0, 1, 2, 3, 4, 5, 6


class Fields:
    """Reads big-endian fields one after the other from a package body."""

    def __init__(self, data: bytes) -> None:
        self.data, self.at = data, 0

    def take(self, fmt: str):
        values = struct.unpack_from('>' + fmt, self.data, self.at)
        self.at += struct.calcsize('>' + fmt)
        return values if len(values) > 1 else values[0]

    def rest(self) -> bytes:
        data, self.at = self.data[self.at:], len(self.data)
        return data


def decode_message(body: bytes) -> dict:
    """A ROBOT_MESSAGE body: timestamp [us], source, type and the fields of the four types ur_sim sends."""
    f = Fields(body)
    out = {'timestamp': f.take('Q'), 'source': f.take('b'), 'type': f.take('B')}
    if out['type'] == VERSION:
        name = f.data[f.at + 1:f.at + 1 + f.take('b')]
        f.at += len(name)
        out.update(project=name.decode(), version=(f.take('B'), f.take('B'), f.take('i'), f.take('i')),
                   build_date=f.rest().decode())
    elif out['type'] == KEY:
        out.update(code=f.take('i'), argument=f.take('i'))
        title = f.data[f.at + 1:f.at + 1 + f.take('B')]
        f.at += len(title)
        out.update(title=title.decode(), text=f.rest().decode())
    elif out['type'] == RUNTIME_EXCEPTION:
        out.update(line=f.take('I'), column=f.take('I'), text=f.rest().decode())
    elif out['type'] == TEXT:
        out.update(text=f.rest().decode())
    return out


def decode_state(body: bytes) -> dict[int, Fields]:
    """A ROBOT_STATE body: sub-package type -> its fields (after size and type)."""
    subs, at = {}, 0
    while at < len(body):
        size, kind = struct.unpack_from('>IB', body, at)
        assert size >= 5 and at + size <= len(body), 'a sub-package runs past its package'
        subs[kind] = Fields(body[at + 5:at + size])
        at += size
    return subs


def robot_mode(f: Fields) -> dict:
    names = ('timestamp', 'connected', 'enabled', 'power_on', 'emergency_stopped', 'protective_stopped',
             'program_running', 'program_paused', 'robot_mode', 'control_mode', 'target_speed_fraction',
             'speed_scaling', 'target_speed_fraction_limit')
    return dict(zip(names, [f.take('Q'), *(bool(f.take('B')) for _ in range(7)), f.take('b'), f.take('B'),
                            f.take('d'), f.take('d'), f.take('d')]))


class Client:
    """A primary interface client: reads packages (int32 size with itself, uint8 type) and sends script text."""

    def __init__(self, address: tuple[str, int], rcvbuf: int | None = None) -> None:
        self.sock = socket.socket()
        if rcvbuf is not None:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(TIMEOUT)
        self.sock.connect(address)

    def _read(self, n: int) -> bytes:
        return recv_exactly(self.sock, n)

    def package(self) -> tuple[int, bytes]:
        size, kind = struct.unpack('>iB', self._read(5))
        return kind, self._read(size - 5)

    def message(self) -> dict:
        """The next robot message (robot state packages before it are skipped)."""
        while True:
            kind, body = self.package()
            if kind == MESSAGE:
                return decode_message(body)

    def state(self) -> dict[int, Fields]:
        """The next robot state (messages before it are skipped)."""
        while True:
            kind, body = self.package()
            if kind == STATE:
                return decode_state(body)

    def send(self, text: str) -> None:
        self.sock.sendall(text.encode())

    def closed(self) -> bool:
        """Whether the server closed the connection (what it sent before is read past)."""
        try:
            while self.sock.recv(65536):
                pass
            return True
        except ConnectionResetError:
            return True

    def close(self) -> None:
        self.sock.close()


@pytest.fixture(scope='module')
def h():
    with running_sim() as harness:
        yield harness


def _open(h, monkeypatch, **kwargs) -> PrimaryPort:
    """A port of the test's own on the harness's robot, ticked after every control cycle as the node ticks its
    ports."""
    port = PrimaryPort('127.0.0.1', 0, h.sim.host, **kwargs)
    step = h.sim.step_once

    def step_and_tick() -> None:
        step()
        port.tick()
    monkeypatch.setattr(h.sim, 'step_once', step_and_tick)
    return port


@pytest.fixture
def port(h):
    """The node's primary interface (its parameters: port 0, any free one)."""
    return h.sim.primary_ports[0]


@pytest.fixture
def client(port):
    c = Client(port.address)
    yield c
    c.close()


def _cycles(h, n: int) -> None:
    end = h.sim.sim.time + (n - 0.5) * h.sim.sim.control_dt
    wait_for(lambda: h.sim.sim.time >= end, what=f'{n} control cycles')


def _states(h, client: Client, n: int) -> list[dict[int, Fields]]:
    """`n` robot states: the one of the next cycle (a new port's first tick sends one), then one per 50 cycles
    (100 ms at 500 Hz: each span holds one 100 ms boundary)."""
    states = []
    for k in range(n):
        _cycles(h, 50 if k else 1)
        states.append(client.state())
    return states


def test_the_version_message_comes_first_with_the_robot_software(h, client):
    kind, body = client.package()
    assert kind == MESSAGE
    msg = decode_message(body)
    v = h.sim.host.cfg.software_version
    assert msg['type'] == VERSION and msg['project'] == 'URControl' and msg['source'] == -2
    assert msg['version'] == (v.major, v.minor, v.bugfix, v.build)


def test_the_robot_state_every_100_ms_with_modes_flags_and_kinematics(h, client):
    client.message()  # the version
    states = _states(h, client, 4)
    modes = [robot_mode(s[ROBOT_MODE]) for s in states]
    assert np.allclose(np.diff([m['timestamp'] for m in modes[1:]]), 100_000, atol=1)
    for m in modes:
        assert m['robot_mode'] == RUNNING and m['power_on'] and m['program_running'] and not m['program_paused']
        assert not m['protective_stopped'] and not m['emergency_stopped']
        assert m['speed_scaling'] == pytest.approx(h.sim.scaling.factor)
        assert m['target_speed_fraction'] == pytest.approx(h.sim.scaling.slider)
    # in the order the robot sends them (a client such as python-urx needs the robot mode first)
    assert list(states[0]) == [ROBOT_MODE, JOINT, CARTESIAN, KINEMATICS, MASTERBOARD, TOOL, CONFIGURATION]
    kin = states[0][KINEMATICS]
    kin.take('6I')
    theta, a, d, alpha = (kin.take('6d') for _ in range(4))
    dh = h.sim.sim.params.dh
    assert np.allclose(a, [0, dh.a2, dh.a3, 0, 0, 0]) and np.allclose(d, [dh.d1, 0, 0, dh.d4, dh.d5, dh.d6])
    assert np.allclose(alpha, [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]) and not any(theta)
    config = states[0][CONFIGURATION]
    limits = np.reshape(config.take('12d'), (6, 2))
    assert np.allclose(limits[:, 0], h.sim.sim.params.q_min) and np.allclose(limits[:, 1], h.sim.sim.params.q_max)
    config.take('12d5d24d')
    assert config.take('4i')[2] == 1  # UR5: the ur5e's robot type
    board = states[0][MASTERBOARD]
    board.take('IIBBddbbdd4f')
    assert board.take('B') == h.sim.robot.safety_mode


def test_joint_cartesian_and_tool_data_are_the_robots(h, client):
    client.message()  # the version
    _cycles(h, 50)  # a 100 ms boundary: one state
    state = client.state()
    joints = [state[JOINT].take('3d4fB') for _ in range(6)]  # per joint, interleaved
    assert state[JOINT].rest() == b''
    assert np.allclose([j[0] for j in joints], h.q, atol=1e-4) and np.allclose([j[1] for j in joints], h.q, atol=1e-3)
    with h.sim.host.lock:  # as RTDE's actual_current (the same reader); the state is of a cycle or more before
        currents = motor_currents(h.sim.sim)
    assert np.allclose([j[3] for j in joints], currents, atol=0.01)  # the arm at rest: the current's jitter [A]
    assert all(np.isnan(j[4:6]).all() and j[6] == 0.0 and j[7] == 253 for j in joints)  # not simulated; RUNNING
    pose = state[CARTESIAN].take('6d')
    assert state[CARTESIAN].take('6d') == (0.0,) * 6 and state[CARTESIAN].rest() == b''  # no TCP offset
    with h.sim.host.lock:
        position, quat = h.sim.sim.tcp_pose()
    assert np.allclose(pose[:3], position, atol=1e-4)
    assert np.allclose(Rotation.from_rotvec(pose[3:]).as_matrix(), Rotation.from_quat(quat).as_matrix(), atol=1e-4)
    ranges, inputs, supply, volts, current, temperature, mode = (state[TOOL].take(f) for f in ('BB', 'dd', 'f', 'B',
                                                                                              'f', 'f', 'B'))
    assert state[TOOL].rest() == b''
    io = h.sim.sim.io
    assert np.allclose(inputs, io.tool_analog_in) and volts == io.tool_voltage and mode == 253
    assert np.isnan([supply, current, temperature]).all() and set(ranges) <= {0, 1}


def test_a_line_of_bare_statements_runs_as_a_program(h, client):
    assert not h.sim.sim.io.digital_out[1]
    client.send('set_standard_digital_out(1, True)\n')
    started = client.message()
    while started['type'] != KEY:
        started = client.message()
    assert started['title'] == 'PROGRAM_XXX_STARTED'
    wait_for(lambda: h.sim.sim.io.digital_out[1], what='digital output 1 on')
    wait_for(lambda: h.sim.host.scripts.current is None, what='the program to end')
    assert not h.sim.robot.program_running  # the program replaced the External Control program


def test_a_def_program_reports_started_text_and_stopped_and_a_secondary_sends_state_only(h, client):
    secondary = h.sim.primary_ports[1]
    second = Client(secondary.address)
    try:
        assert decode_message(second.package()[1])['type'] == VERSION
        client.message()  # the version
        second.send('def hello():\n  textmsg("hi there")\n')  # a program in two parts, on the secondary port
        second.send('  sleep(0.1)\nend\n')
        started = client.message()
        assert (started['type'], started['title'], started['text']) == (KEY, 'PROGRAM_XXX_STARTED', 'hello')
        wait_for(lambda: h.sim.host.scripts.current is None, what='the program to end')
        text, stopped = client.message(), client.message()
        assert (text['type'], text['text']) == (TEXT, 'hi there')
        assert (stopped['type'], stopped['title'], stopped['text']) == (KEY, 'PROGRAM_XXX_STOPPED', 'hello')
        assert started['timestamp'] < stopped['timestamp']
        _cycles(h, 50)  # a state after the program's end
        kinds = []
        while True:  # everything the secondary client was sent up to that state: states only
            kind, body = second.package()
            kinds.append(kind)
            if kind == STATE and robot_mode(decode_state(body)[ROBOT_MODE])['timestamp'] > stopped['timestamp']:
                break
        assert set(kinds) == {STATE}
    finally:
        second.close()


def test_a_runtime_error_and_a_syntax_error_give_runtime_exceptions_with_the_line(h, client):
    client.message()  # the version
    client.send('def oops():\n  textmsg("before")\n  no_such_function()\nend\n')
    messages = [client.message()]  # started: submitted
    wait_for(lambda: h.sim.host.scripts.current is None, what='the program to end')
    messages += [client.message() for _ in range(3)]
    assert [m['type'] for m in messages] == [KEY, TEXT, RUNTIME_EXCEPTION, KEY]
    error = messages[2]
    assert (error['line'], error['column']) == (3, 3) and 'no_such_function' in error['text']
    assert messages[3]['title'] == 'PROGRAM_XXX_STOPPED'
    client.send('def broken():\n  x = \nend\n')
    error = client.message()
    assert error['type'] == RUNTIME_EXCEPTION and error['line'] == 3 and error['column'] > 0  # at 'end': no value
    assert h.sim.host.scripts.current is None  # nothing runs


def test_controller_commands_stop_the_program_power_off_and_release_the_brakes(h, client):
    client.message()  # the version
    client.send('def forever():\n  while True:\n    sync()\n  end\nend\n')
    assert client.message()['title'] == 'PROGRAM_XXX_STARTED'
    client.send('stop program\n')
    wait_still(lambda: h.sim.robot.program_state == STOPPED, what='the program stopped')
    wait_for(lambda: h.sim.host.scripts.current is None, what='the program to end')
    stopped = client.message()
    assert (stopped['title'], stopped['text']) == ('PROGRAM_XXX_STOPPED', 'forever')
    client.send('power off\n')
    wait_still(lambda: h.sim.robot.robot_mode == POWER_OFF, what='the robot powered off')
    client.send('set robotmode run\n')  # from POWER_OFF: powers on, then releases the brakes
    wait_still(lambda: h.sim.robot.robot_mode == POWER_ON, what='the robot powered on')
    wait_for(lambda: h.sim.robot.robot_mode == RUNNING, what='the robot mode RUNNING')


def test_a_client_that_never_reads_does_not_hold_up_the_others(h, monkeypatch):
    port = _open(h, monkeypatch, backlog=8)
    idle = Client(port.address, rcvbuf=4096)
    reader = Client(port.address)
    try:
        reader.message()  # the version
        stamps = [robot_mode(s[ROBOT_MODE])['timestamp'] for s in _states(h, reader, 1)]
        # The reader takes every state as it comes; the idle client's kernel buffers fill, then its queue.
        full = 0  # successive states before which the idle client's queue was full: its sender waits on the kernel
        while full < 5:
            assert len(stamps) < 2000, 'the idle client never filled its queue'
            full = full + 1 if max(port.queued) == 8 else 0
            _cycles(h, 50)
            stamps.append(robot_mode(reader.state()[ROBOT_MODE])['timestamp'])
        assert np.allclose(np.diff(stamps[1:]), 100_000, atol=1)  # the reader lost none, none came late
        assert sorted(port.queued) == [0, 8]
        # What the idle client finally reads is whole packages in order: the version, the states its buffers
        # held, then the newest eight.
        assert decode_message(idle.package()[1])['type'] == VERSION
        seen = [robot_mode(idle.state()[ROBOT_MODE])['timestamp']]
        while seen[-1] != stamps[-1]:
            seen.append(robot_mode(idle.state()[ROBOT_MODE])['timestamp'])
        assert set(seen) <= set(stamps) and seen == sorted(seen) and len(seen) < len(stamps)  # the oldest dropped
        assert seen[-8:] == stamps[-8:]
    finally:
        idle.close()
        reader.close()
        port.close()


def test_input_that_is_not_text_or_too_long_closes_the_connection_and_its_threads(port):
    for data in (b'textmsg("\xff\xfe")\n', b'#' * (MAX_SCRIPT + 1)):
        c = Client(port.address)
        try:
            try:
                c.sock.sendall(data)
            except (BrokenPipeError, ConnectionResetError):
                pass  # closed while it sent
            assert c.closed()
        finally:
            c.close()
    wait_still(lambda: port.clients == 0 and not any(t.name == 'primary_interface_sender'
                                                     for t in threading.enumerate()), what='the connections to end')


def test_the_layouts_follow_the_software_version(h):
    """RobotModeData ends with a reserved byte from 3.5 on; ConfigurationData has two reserved int16 from 5.25.1 on."""
    host, params = h.sim.host, h.sim.sim.params
    with host.lock:
        sizes = {v: len(pm.robot_mode_data(host, SoftwareVersion(*v))) for v in ((3, 4, 0), (3, 5, 0), (5, 12, 6))}
    assert sizes == {(3, 4, 0): 5 + 41, (3, 5, 0): 5 + 42, (5, 12, 6): 5 + 42}
    assert len(pm.configuration_data(params, SoftwareVersion(5, 25, 0))) == 5 + 440
    assert len(pm.configuration_data(params, SoftwareVersion(5, 25, 1))) == 5 + 444
