"""RTDE on its TCP port, spoken by a client written from the RTDE guide: protocol and version, output recipes
streamed in simulated time with the robot's values, NOT_FOUND and IN_USE, inputs that change the robot (seen on
the ROS side), pause."""
from __future__ import annotations

import json
import os
import socket
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from port_helpers import recv_exactly
from scipy.spatial.transform import Rotation
from sim_harness import point, running_sim, wait_for, wait_still

from ur_glue_planner.motion.kinematics import Kinematics
from ur_sim_driver.ports import rtde_protocol as rp
from ur_sim_driver.ports.rtde_port import BACKLOG
from ur_sim_driver.robot.motor_currents import current_as_torque, motor_currents

TIMEOUT = 10.0  # [s] of wall time for an answer


class RtdeClient:
    """The client side of the protocol (big-endian: size, type, payload)."""

    def __init__(self, address: tuple[str, int], receive_buffer: int | None = None) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if receive_buffer is not None:  # before connecting: the window the server may fill
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
        self.sock.settimeout(TIMEOUT)
        self.sock.connect(address)

    def close(self) -> None:
        self.sock.close()

    def _read(self, n: int) -> bytes:
        return recv_exactly(self.sock, n)

    def receive(self) -> tuple[int, bytes]:
        size, kind = struct.unpack('>HB', self._read(3))
        return kind, self._read(size - 3)

    def request(self, kind: int, payload: bytes = b'') -> bytes:
        self.sock.sendall(struct.pack('>HB', 3 + len(payload), kind) + payload)
        while True:  # data packages of a started recipe may come first
            got, answer = self.receive()
            if got == kind:
                return answer

    def outputs(self, frequency: float, names: list[str]) -> tuple[int, list[str]]:
        answer = self.request(ord('O'), struct.pack('>d', frequency) + ','.join(names).encode())
        return answer[0], answer[1:].decode().split(',')

    def inputs(self, names: list[str]) -> tuple[int, list[str]]:
        answer = self.request(ord('I'), ','.join(names).encode())
        return answer[0], answer[1:].decode().split(',')

    def data(self) -> tuple[int, bytes]:
        while True:
            kind, payload = self.receive()
            if kind == ord('U'):
                return payload[0], payload[1:]


def _unpack(types: list[str], payload: bytes) -> list:
    fmt = rp.recipe_format(types)
    return rp.regroup(fmt.unpack(payload[:fmt.size]), types)


@pytest.fixture(scope='module')
def h():
    with running_sim() as harness:
        yield harness


def _cycles(h, n: int) -> None:
    """Step the simulation `n` control cycles while a connection streams."""
    start = h.sim.rtde_port.cycle
    wait_for(lambda: h.sim.rtde_port.cycle >= start + n, what=f'{n} control cycles')


def _newest(h, client: RtdeClient, types: list[str]) -> list:
    """The values of the package of the last cycle run (the recipe's first variable is `timestamp`): the
    simulation holds still between waits, so they are the robot's values now."""
    while True:
        values = _unpack(types, client.data()[1])
        if values[0] == pytest.approx(h.sim.sim.time, abs=1e-9):
            return values[1:]


def _connect(h, receive_buffer: int | None = None) -> RtdeClient:
    client = RtdeClient(h.sim.rtde_port.address, receive_buffer)
    assert client.request(ord('V'), struct.pack('>H', 2)) == b'\x01'
    return client


def test_a_robot_before_5_23_does_not_know_current_as_torque():
    """As every robot before 5.23.0 / 10.11.0 (and every CB3): actual_current_as_torque is NOT_FOUND. First in the
    module: its ur_sim shares the test process's domain, so it must be gone before the module's starts."""
    with running_sim(software_version='5.22.2') as older:
        client = _connect(older)
        try:
            recipe, types = client.outputs(500.0, ['actual_q', 'actual_current_as_torque'])
            assert recipe == 0 and types == ['VECTOR6D', 'NOT_FOUND']
        finally:
            client.close()


def test_version_and_an_output_recipe_streamed_in_simulated_time(h):
    client = _connect(h)
    try:
        major, minor, bugfix, build = struct.unpack('>IIII', client.request(ord('v')))
        assert (major, minor, bugfix, build) == tuple(h.sim.host.dashboard.version)
        names = ['timestamp', 'actual_q', 'robot_mode', 'actual_digital_output_bits', 'speed_scaling']
        recipe, types = client.outputs(125.0, names)
        assert recipe == 1 and types == ['DOUBLE', 'VECTOR6D', 'INT32', 'UINT64', 'DOUBLE']
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 20)  # 5 periods of 125 Hz at 500 Hz
        stamps = []
        for _ in range(5):
            got, payload = client.data()
            assert got == 1
            t, q, mode, outputs, scaling = _unpack(types, payload)
            stamps.append(t)
            assert np.allclose(q, h.q, atol=1e-3) and mode == 7 and scaling == pytest.approx(1.0)
        assert np.allclose(np.diff(stamps), 0.008, atol=1e-9)  # every 4th cycle of 500 Hz, read in that cycle
        assert client.request(ord('P')) == b'\x01'
    finally:
        client.close()


def test_the_tcp_speed_is_the_rate_of_the_tcp_pose(h):
    """actual_TCP_speed (linear [m/s], angular [rad/s], base axes) against the change of actual_TCP_pose over the
    step before it, at 500 Hz during a move of every joint (MuJoCo's semi-implicit Euler moves the arm in a step by
    the velocity at the step's end)."""
    client = _connect(h)
    try:
        names = ['timestamp', 'actual_TCP_pose', 'actual_TCP_speed']
        recipe, types = client.outputs(500.0, names)
        assert recipe == 1
        handle = h.send(h.goal([point(h.q + np.array([0.3, -0.2, 0.25, 0.3, -0.3, 0.4]), 1.0, [0.0] * 6)]))
        assert handle.accepted
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 200)  # 0.4 s of the 1 s move
        rows = [_unpack(types, client.data()[1]) for _ in range(200)]
        assert client.request(ord('P')) == b'\x01'
        h.result(handle)
    finally:
        client.close()
    t = np.array([r[0] for r in rows])
    pose, speed = np.array([r[1] for r in rows]), np.array([r[2] for r in rows])
    assert np.allclose(np.diff(t), 0.002, atol=1e-9)
    linear = (pose[1:, :3] - pose[:-1, :3]) / 0.002
    rotations = Rotation.from_rotvec(pose[:, 3:])
    angular = (rotations[1:] * rotations[:-1].inv()).as_rotvec() / 0.002  # base axes
    assert np.abs(speed[1:, :3]).max() > 0.05 and np.abs(speed[1:, 3:]).max() > 0.5  # it moves
    assert np.allclose(speed[1:, :3], linear, atol=1e-3) and np.allclose(speed[1:, 3:], angular, atol=1e-3)


def test_the_target_tcp_is_where_the_setpoint_puts_it(h):
    """target_TCP_pose and target_TCP_speed against Pinocchio's forward kinematics of the URDF at target_q, and its
    derivative along target_qd (central differences), during a move."""
    client = _connect(h)
    try:
        names = ['target_q', 'target_qd', 'target_TCP_pose', 'target_TCP_speed']
        recipe, types = client.outputs(50.0, names)
        assert recipe == 1 and types == ['VECTOR6D'] * 4
        handle = h.send(h.goal([point(h.q + np.array([0.3, -0.2, 0.25, 0.3, -0.3, 0.4]), 1.0, [0.0] * 6)]))
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 200)
        rows = [_unpack(types, client.data()[1]) for _ in range(10)]
        assert client.request(ord('P')) == b'\x01'
        h.result(handle)
    finally:
        client.close()
    kin = {frame: Kinematics(h.sim.sim.urdf, h.joints, frame) for frame in ('base', 'tool0')}

    def tcp(q):
        q = np.asarray(q)
        return np.linalg.inv(kin['base'].fk(q)) @ kin['tool0'].fk(q)

    moving = 0
    for q, qd, pose, speed in rows:
        expected = tcp(q)
        assert np.allclose(pose[:3], expected[:3, 3], atol=1e-6)
        assert np.allclose(Rotation.from_rotvec(pose[3:]).as_matrix(), expected[:3, :3], atol=1e-6)
        eps = 1e-6
        ahead, behind = tcp(np.add(q, np.multiply(qd, eps))), tcp(np.subtract(q, np.multiply(qd, eps)))
        linear = (ahead[:3, 3] - behind[:3, 3]) / (2 * eps)
        angular = Rotation.from_matrix(ahead[:3, :3] @ behind[:3, :3].T).as_rotvec() / (2 * eps)
        assert np.allclose(speed[:3], linear, atol=1e-6) and np.allclose(speed[3:], angular, atol=1e-6)
        moving += np.abs(speed).max() > 0.05
    assert moving >= 5


def test_joint_modes_elbow_raw_wrench_and_currents_are_filled_and_what_is_not_simulated_is_nan(h):
    client = _connect(h)
    try:
        names = ['timestamp', 'joint_mode', 'elbow_position', 'elbow_velocity', 'ft_raw_wrench', 'actual_current',
                 'actual_main_voltage', 'actual_tool_accelerometer']
        recipe, types = client.outputs(500.0, names)
        assert recipe == 1 and 'NOT_FOUND' not in types
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 2)
        modes, elbow, elbow_v, raw, current, voltage, accelerometer = _newest(h, client, types)
        assert list(modes) == [253] * 6  # RUNNING, as the robot mode
        with h.sim.host.lock:  # the forearm link's origin in the base frame, from MuJoCo directly
            d, physics = h.sim.sim.physics.data, h.sim.sim.physics
            forearm, base = physics.body_id('forearm_link'), physics.body_id('base')
            expected = d.xmat[base].reshape(3, 3).T @ (d.xpos[forearm] - d.xpos[base])
        assert np.allclose(elbow, expected, atol=1e-3) and np.linalg.norm(elbow) > 0.3  # the arm holds still
        assert np.allclose(elbow_v, 0.0, atol=1e-3)
        assert np.isfinite(raw).all()
        with h.sim.host.lock:
            expected_current = motor_currents(h.sim.sim)  # the arm holds still: the currents of gravity
        assert np.allclose(current, expected_current, rtol=1e-12, atol=1e-12)
        assert np.isnan(voltage) and np.isnan(accelerometer).all()
    finally:
        client.close()


def test_every_output_variable_is_served_with_its_type(h):
    """The whole output table in one recipe, as the Client Library's exhaustive test recipe asks for it."""
    names = list(rp.OUTPUTS)
    client = _connect(h)
    try:
        recipe, types = client.outputs(500.0, names)
        assert recipe == 1 and types == [rp.OUTPUTS[n] for n in names]
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 2)
        first = dict(zip(names, _unpack(types, client.data()[1])))
        second = dict(zip(names, _unpack(types, client.data()[1])))
    finally:
        client.close()
    assert second['control_step'] == first['control_step'] + 1
    assert second['timestamp'] == pytest.approx(second['control_step'] * 0.002)
    assert first['tool_mode'] == 253 and first['tool_temperature'] == 32.0 and first['tool_output_current'] == 0.0
    assert np.allclose(first['target_gravity'], [0.0, 0.0, 9.81], atol=0.01)  # the anti-gravity: up
    assert first['tcp_force_scalar'] == pytest.approx(np.linalg.norm(first['actual_TCP_force'][:3]))
    assert first['euromap67_input_bits'] == 0 and np.isnan(first['actual_TCP_acceleration']).all()


def test_unknown_names_answer_not_found_and_a_held_input_in_use(h):
    first, second = _connect(h), _connect(h)
    try:
        recipe, types = first.outputs(500.0, ['actual_q', 'no_such_variable', 'euromap67_input_bits'])
        assert recipe == 0 and types == ['VECTOR6D', 'NOT_FOUND', 'UINT32']  # a name the robot knows is typed
        recipe, types = first.outputs(1000.0, ['actual_q'])  # above the robot's 500 Hz
        assert recipe == 0
        assert first.inputs(['input_int_register_24'])[0] == 1
        recipe, types = second.inputs(['input_int_register_24', 'input_int_register_25'])
        assert recipe == 0 and types == ['IN_USE', 'INT32']
        first.close()  # a closed connection lets go of its inputs
        wait_still(lambda: second.inputs(['input_int_register_24'])[0] != 0, what='the register released')
    finally:
        first.close()
        second.close()


def test_current_as_torque_is_the_drive_torques_less_gravity(h):
    """actual_current_as_torque on 5.25.1: the drive torques less the believed gravity (a 5.22 robot does not know
    the name: test_a_robot_before_5_23_does_not_know_current_as_torque)."""
    client = _connect(h)
    try:
        recipe, types = client.outputs(500.0, ['timestamp', 'actual_current_as_torque', 'target_moment'])
        assert recipe == 1 and types == ['DOUBLE', 'VECTOR6D', 'VECTOR6D']
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 2)
        torques, moments = _newest(h, client, types)
        with h.sim.host.lock:
            expected = current_as_torque(h.sim.sim)
            gravity = h.sim.sim.gravity_compensation()
        assert np.allclose(torques, expected, rtol=1e-12, atol=1e-12)
        assert np.abs(torques).max() < 0.1 and np.allclose(moments, gravity, atol=0.1)  # at rest: gravity taken off
    finally:
        client.close()


def test_inputs_change_the_robot_and_show_on_the_ros_side(h):
    client = _connect(h)
    try:
        names = ['standard_digital_output_mask', 'standard_digital_output', 'input_double_register_3']
        recipe, types = client.inputs(names)
        assert recipe == 1 and types == ['UINT8', 'UINT8', 'DOUBLE']
        out_recipe, out_types = client.outputs(500.0, ['actual_digital_output_bits', 'input_double_register_3'])
        assert client.request(ord('S')) == b'\x01'
        payload = struct.pack('>BBBd', recipe, 0b0000_0100, 0b0000_0100, 2.5)  # pin 2 on
        client.sock.sendall(struct.pack('>HB', 3 + len(payload), ord('U')) + payload)
        wait_still(lambda: h.sim.sim.io.digital_out[2], what='digital output 2 on')
        streamed = h.sim.rtde_port.cycle
        _cycles(h, 1)
        while True:  # the packages of the cycles before the input are queued first
            _, data = client.data()
            bits, register = _unpack(out_types, data)
            if bits & 0b100:
                break
        assert register == 2.5 and h.sim.rtde_port.cycle > streamed
        with h.sim.host.lock:  # when each input was last written, in robot time (URScript's rtde_set_watchdog)
            written, now = dict(h.sim.robot.rtde_inputs), h.sim.sim.time
        assert set(names) <= set(written) and all(written[n] <= now for n in names)
        payload = struct.pack('>BBBd', recipe, 0b0000_0100, 0, 0.0)  # pin 2 off again
        client.sock.sendall(struct.pack('>HB', 3 + len(payload), ord('U')) + payload)
        wait_still(lambda: not h.sim.sim.io.digital_out[2], what='digital output 2 off')
    finally:
        client.close()


def test_an_external_force_torque_sensor_feeds_the_robots_reading_once_a_program_enables_it(h):
    client = _connect(h)
    try:
        recipe, types = client.inputs(['external_force_torque'])
        assert recipe == 1 and types == ['VECTOR6D']
        _, out_types = client.outputs(500.0, ['actual_TCP_force', 'ft_raw_wrench'])
        assert client.request(ord('S')) == b'\x01'
        reading = (0.0, 0.0, -20.0, 0.0, 0.0, 0.0)  # 20 N pushing up the tool, in the sensor's (tool0's) axes
        payload = struct.pack('>B6d', recipe, *reading)
        client.sock.sendall(struct.pack('>HB', 3 + len(payload), ord('U')) + payload)
        wait_for(lambda: h.sim.sim.external_ft_input[2] == -20.0, what='the input taken')
        assert abs(h.sim.sim.wrench()[2]) < 5.0  # not the robot's reading until a program enables the sensor
        with h.sim.host.lock:
            h.sim.host.scripts.submit('ft_rtde_input_enable(True)')
        wait_for(lambda: h.sim.sim.external_ft is not None, what='the external sensor enabled')
        while True:  # the packages of the cycles before are queued first
            force, raw = _unpack(out_types, client.data()[1])
            if raw[2] == -20.0:
                break
        rot = Rotation.from_quat(h.sim.sim.physics.tcp_pose()[1]).as_matrix()
        assert np.allclose(force[:3], rot @ reading[:3], atol=1e-9) and np.allclose(raw, reading)
    finally:
        client.close()
        with h.sim.host.lock:
            h.sim.host.scripts.submit('ft_rtde_input_enable(False)')
        wait_for(lambda: h.sim.sim.external_ft is None, what='the external sensor disabled')


def test_a_refused_input_leaves_the_data_stream_alone_and_the_slider_takes_zero(h):
    """The Client Library's RTDE example sweeps the slider from 0 to 1 while it reads data packages only (any
    other package is a failure to it): 0 is taken, 1.5 refused in ur_sim's log, and only data packages come."""
    client = _connect(h)

    def slider(fraction: float) -> None:
        payload = struct.pack('>BId', recipe, 1, fraction)
        client.sock.sendall(struct.pack('>HB', 3 + len(payload), ord('U')) + payload)

    def applied(fraction: float):
        return lambda: h.sim.host.speed_scaling.slider == fraction
    try:
        recipe, _ = client.inputs(['speed_slider_mask', 'speed_slider_fraction'])
        _, out_types = client.outputs(500.0, ['timestamp'])
        assert client.request(ord('S')) == b'\x01'
        slider(0.0)
        wait_for(applied(0.0), what='the slider at 0')
        slider(1.5)  # refused
        slider(0.5)  # taken after it, on the same connection: once it shows, the refusal has been handled
        wait_for(applied(0.5), what='the slider at 0.5')
        with h.sim.host.lock:
            now = h.sim.sim.time
        while True:  # every package queued up to now: data packages only
            kind, payload = client.receive()
            assert kind == ord('U'), bytes(payload)
            (stamp,) = _unpack(out_types, payload[1:])
            if stamp >= now - 1e-9:
                break
    finally:
        slider(1.0)
        wait_for(applied(1.0), what='the slider back at 1')
        client.close()


def test_a_ur_rtde_program_reads_the_robot_and_sets_an_output():
    """ur_rtde (PyPI ur-rtde), as its users run it, against ur_sim's RTDE on 30004: on a loopback address of this
    test process's own (ur_rtde has no port argument; ROS_DOMAIN_ID is unique per process), paced to the wall clock
    that ur_rtde waits on."""
    address = f'127.0.0.{10 + int(os.environ.get("ROS_DOMAIN_ID", "0")) % 240}'
    with running_sim(rtde={'host': address, 'port': 30004}, paced=True) as h:
        run = subprocess.run([sys.executable, str(Path(__file__).with_name('ur_rtde_client.py')), address],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        read = json.loads(run.stdout.strip().splitlines()[-1])
        assert read['connected'] and read['timestamp'] > 0.0 and read['set_output']
        assert (read['robot_mode'], read['safety_mode'], read['runtime_state']) == (7, 1, 2)  # RUNNING, NORMAL, PLAYING
        assert read['speed_scaling'] == pytest.approx(1.0)
        q = np.array(read['q'])
        assert np.allclose(q, h.q, atol=1e-4)  # the arm holds still
        # The pose in the robot's base frame (ROS 'base'), checked against Pinocchio's FK of the URDF.
        fk = {frame: Kinematics(h.sim.sim.urdf, h.joints, frame).fk(q) for frame in ('base', 'tool0')}
        expected = np.linalg.inv(fk['base']) @ fk['tool0']
        pose = np.array(read['tcp'])
        assert np.allclose(pose[:3], expected[:3, 3], atol=1e-6)
        assert np.allclose(Rotation.from_rotvec(pose[3:]).as_matrix(), expected[:3, :3], atol=1e-6)
        wait_still(lambda: h.sim.sim.io.digital_out[3], what='digital output 3, set through RTDE')


def test_protocol_one_has_no_output_recipe_ids_and_streams_at_the_control_rate(h):
    """A client that never asks for protocol 2 speaks 1: the output set-up has no frequency and its answer no recipe
    id, and the data packages carry the values alone, every control cycle."""
    client = RtdeClient(h.sim.rtde_port.address)
    try:
        answer = client.request(ord('O'), b'timestamp,robot_mode')
        assert answer.decode() == 'DOUBLE,INT32'
        assert client.request(ord('S')) == b'\x01'
        _cycles(h, 3)
        stamps = []
        for _ in range(3):
            while True:
                kind, payload = client.receive()
                if kind == ord('U'):
                    break
            t, mode = struct.unpack('>di', payload)
            stamps.append(t)
            assert mode == 7
        assert np.allclose(np.diff(stamps), 0.002, atol=1e-9)
        assert client.request(ord('P')) == b'\x01'
    finally:
        client.close()


def _closed(client: RtdeClient) -> bool:
    """The server has closed the connection (a read gets end of file)."""
    client.sock.settimeout(TIMEOUT)
    try:
        return client.sock.recv(1) == b''
    except ConnectionResetError:
        return True


def test_malformed_packages_close_that_connection_only(h):
    other = _connect(h)
    try:
        recipe, types = other.outputs(500.0, ['timestamp'])
        assert other.request(ord('S')) == b'\x01'
        for bad in (struct.pack('>HB', 2, ord('V')),  # a size below the header's
                    struct.pack('>HB', 3, ord('Z')),  # an unknown package type
                    struct.pack('>HBB', 4, ord('V'), 2)):  # a version request one byte short
            client = _connect(h)
            client.sock.sendall(bad)
            assert _closed(client), bad
            client.close()
        client = _connect(h)  # input data shorter than its recipe
        assert client.inputs(['input_int_register_30'])[0] == 1
        client.sock.sendall(struct.pack('>HBBH', 6, ord('U'), 1, 7))
        assert _closed(client)
        client.close()
        _cycles(h, 3)
        stamps = [struct.unpack('>d', other.data()[1][:8])[0] for _ in range(3)]
        assert np.allclose(np.diff(stamps), h.sim.sim.control_dt)  # the other connection streams on
    finally:
        other.close()


def test_an_oversized_recipe_is_refused_naming_the_limit(h):
    client = _connect(h)
    try:
        recipe, types = client.outputs(500.0, ['actual_q'] * 1400)  # 1400 x 48 bytes a package
        assert recipe == 0 and types == ['VECTOR6D'] * 1400
        kind, text = client.receive()
        assert kind == ord('M') and b'67204 bytes is over the package limit of 65535 bytes' in text
        assert client.outputs(500.0, ['actual_q'] * 1300)[0] == 1  # 62404 bytes: within it
    finally:
        client.close()


def test_a_client_that_never_reads_holds_up_neither_the_simulation_nor_others(h):
    idle, reader = _connect(h, receive_buffer=4096), _connect(h)
    try:
        for client in (idle, reader):
            client.outputs(500.0, ['timestamp', 'actual_q', 'actual_qd', 'target_q'])
            assert client.request(ord('S')) == b'\x01'
        t0 = h.sim.sim.time
        for _ in range(6):  # 3000 cycles: more than the queue and the socket buffers hold
            _cycles(h, 500)
            while struct.unpack('>d', reader.data()[1][:8])[0] < h.sim.sim.time - 1e-9:
                pass  # the reader keeps up
        assert h.sim.sim.time - t0 >= 3000 * h.sim.sim.control_dt - 1e-9
        assert sorted(len(s._out) for s in h.sim.rtde_port._sessions)[-1] == BACKLOG  # the idle one's, full
    finally:
        idle.close()
        reader.close()
