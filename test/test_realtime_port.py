"""The real-time interface on its TCP port (30003 on a UR), read by a decoder of our own: a package every control
cycle in simulated time, its size by software version, its fields equal to the robot's, and URScript from a client
run on the robot."""
from __future__ import annotations

import socket
import struct

import numpy as np
import pytest
from port_helpers import recv_exactly
from sim_harness import running_sim, wait_for, wait_still

from ur_sim_driver.ports.primary_port import REALTIME
from ur_sim_driver.ports.realtime_messages import LAYOUT, package_size
from ur_sim_driver.robot.motor_currents import motor_currents
from ur_sim_driver.robot.software import SoftwareVersion

pytestmark = pytest.mark.timeout(120)

TIMEOUT = 10.0  # [s] of wall time for a package: it is queued before the test reads it


def _offsets() -> dict[str, tuple[int, int]]:
    """Field -> (index of its first double, count), from the layout and the RTDE guide's sizes of each field."""
    counts = {'target_q': 6, 'target_qd': 6, 'target_qdd': 6, 'target_current': 6, 'target_moment': 6, 'actual_q': 6,
              'actual_qd': 6, 'actual_current': 6, 'joint_control_output': 6, 'actual_TCP_pose': 6,
              'actual_TCP_speed': 6, 'actual_TCP_force': 6, 'target_TCP_pose': 6, 'target_TCP_speed': 6,
              'joint_temperatures': 6, 'joint_mode': 6, 'actual_tool_accelerometer': 3, 'actual_joint_voltage': 6,
              'elbow_position': 3, 'elbow_velocity': 3, 'payload_cog': 3, 'payload_inertia': 6}
    at, out = 0, {}
    for item in LAYOUT:
        n = item if isinstance(item, int) else counts.get(item, 1)
        if not isinstance(item, int):
            out[item] = (at, n)
        at += n
    return out


FIELDS = _offsets()


class Reader:
    def __init__(self, address) -> None:
        self.sock = socket.create_connection(address, timeout=TIMEOUT)

    def package(self) -> np.ndarray:
        size = struct.unpack('>i', recv_exactly(self.sock, 4))[0]
        return np.array(struct.unpack(f'>{(size - 4) // 8}d', recv_exactly(self.sock, size - 4)))

    def field(self, values: np.ndarray, name: str) -> np.ndarray:
        first, n = FIELDS[name]
        return values[first:first + n]


def _cycles(h, n: int) -> None:
    """Step the simulation `n` control cycles (each queues a package for every connection)."""
    t_end = h.sim.sim.time + (n - 0.5) * h.sim.sim.control_dt
    wait_for(lambda: h.sim.sim.time >= t_end, what=f'{n} control cycles')


@pytest.fixture(scope='module')
def h():
    with running_sim() as harness:
        yield harness


def test_the_layout_sizes_by_software_version():
    assert sum(n for n in (FIELDS[k][1] for k in FIELDS)) + 6 + 6 + 1 + 2 + 3 == 152  # 152 doubles in 5.10+
    sizes = {(3, 1): 1044, (3, 4): 1060, (3, 9): 1108, (3, 13): 1116, (3, 15): 1140, (5, 3): 1108, (5, 8): 1116,
             (5, 9): 1140, (5, 10): 1220, (5, 25): 1220}
    for (major, minor), size in sizes.items():
        assert package_size(SoftwareVersion(major, minor, 0, 0)) == size, (major, minor)
    assert FIELDS['actual_digital_output_bits'][0] * 8 + 4 == 1044  # byte offsets as the robot's table gives them
    assert FIELDS['safety_status'][0] * 8 + 4 == 1108 and FIELDS['payload'][0] * 8 + 4 == 1140


def test_a_package_every_control_cycle_with_the_robots_values(h):
    port = h.sim.primary_ports[2]
    assert port.kind == REALTIME
    reader = Reader(port.address)
    try:
        wait_still(lambda: port.clients == 1, what='the connection')
        _cycles(h, 11)
        first = reader.package()
        assert len(first) == (package_size(port.version) - 4) // 8
        times = [first[0]]
        for _ in range(9):
            times.append(reader.package()[0])
        assert np.allclose(np.diff(times), h.sim.sim.control_dt, atol=1e-9)  # every cycle of simulated time
        values = reader.package()
        while reader.field(values, 'timestamp')[0] != pytest.approx(h.sim.sim.time, abs=1e-9):
            values = reader.package()  # to the last cycle's: the simulation holds still between waits
        assert np.allclose(reader.field(values, 'actual_q'), h.q, atol=1e-4)  # the arm holds still
        assert reader.field(values, 'robot_mode')[0] == 7 and list(reader.field(values, 'joint_mode')) == [253] * 6
        assert reader.field(values, 'safety_mode')[0] == 1 and reader.field(values, 'speed_scaling')[0] == 1.0
        with h.sim.host.lock:
            position, _ = h.sim.sim.tcp_pose()
            currents = motor_currents(h.sim.sim)  # the arm holds still: the currents of gravity
        assert np.allclose(reader.field(values, 'actual_current'), currents, rtol=1e-12, atol=1e-12)
        assert np.allclose(reader.field(values, 'target_current'), currents, rtol=1e-12, atol=1e-12)
        assert np.allclose(reader.field(values, 'actual_TCP_pose')[:3], position, atol=1e-4)
    finally:
        reader.sock.close()
        wait_still(lambda: port.clients == 0, what='the connection closed')


def test_urscript_sent_on_the_port_runs(h):
    port = h.sim.primary_ports[2]
    reader = Reader(port.address)
    try:
        wait_still(lambda: port.clients == 1, what='the connection')
        reader.sock.sendall(b'def set_out():\n  set_standard_digital_out(6, True)\nend\n')
        wait_for(lambda: h.sim.sim.io.digital_out[6], what='digital output 6 set by the program')
        _cycles(h, 1)
        while True:  # the packages of the cycles before come first
            bits = int(reader.field(reader.package(), 'actual_digital_output_bits')[0])
            if bits >> 6 & 1:
                break
    finally:
        reader.sock.sendall(b'set_standard_digital_out(6, False)\n')
        wait_for(lambda: not h.sim.sim.io.digital_out[6], what='digital output 6 off again')
        reader.sock.close()
        wait_still(lambda: port.clients == 0, what='the connection closed')
