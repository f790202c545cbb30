"""The dashboard server on its TCP port: the robot's greeting, one answer line per command line, several clients at
once, and the same interpreter (one robot's state) as the /dashboard_client services."""
from __future__ import annotations

import socket
import threading

import pytest
from sim_harness import running_sim, wait_answer, wait_still
from ur_dashboard_msgs.srv import GetOperationalMode, RawRequest

from ur_sim_driver.ports.dashboard_port import WELCOME, DashboardPort
from ur_sim_driver.ports.tcp_port import MAX_LINE, PortError
from ur_sim_driver.robot.dashboard_server import DashboardServer
from ur_sim_driver.robot.robot_state import RobotState

TIMEOUT = 10.0  # [s] of wall time for a socket answer: the server answers at once, nothing is simulated


class Client:
    """A line-based TCP client, as the Client Library's dashboard client reads and writes."""

    def __init__(self, address: tuple[str, int]) -> None:
        self.sock = socket.create_connection(address, timeout=TIMEOUT)
        self.file = self.sock.makefile('rb')

    def line(self) -> str:
        return self.file.readline().decode().rstrip('\n')

    def ask(self, command: str) -> str:
        self.sock.sendall((command + '\n').encode())
        return self.line()

    def closed(self) -> bool:
        """Whether the server closed the connection (a reset counts: it may close with our bytes still unread)."""
        try:
            return self.file.readline() == b''
        except ConnectionResetError:
            return True

    def close(self) -> None:
        self.file.close()
        self.sock.close()


@pytest.fixture
def port():
    server = DashboardServer(RobotState())
    dashboard = DashboardPort('127.0.0.1', 0, server, threading.Lock())
    try:
        yield dashboard, server
    finally:
        dashboard.close()


def test_greeting_then_one_answer_line_per_command_line(port):
    dashboard, server = port
    client = Client(dashboard.address)
    try:
        assert client.line() == WELCOME
        assert client.ask('robotmode') == 'Robotmode: RUNNING'
        assert client.ask('  PolyscopeVersion ') == server.handle('PolyscopeVersion').answer
        assert client.ask('popup hello\r') == 'showing popup' and server.popup == 'hello'  # CRLF is taken too
        assert client.ask('fly away') == "could not understand: 'fly away'"
        assert client.ask('quit') == 'Disconnected'
        assert client.closed()
    finally:
        client.close()


def test_several_clients_at_once_each_answered_in_its_own_order(port):
    dashboard, _ = port
    clients = [Client(dashboard.address) for _ in range(3)]
    try:
        for c in clients:
            assert c.line() == WELCOME
        for c in reversed(clients):
            c.sock.sendall(b'robotmode\nsafetymode\n')
        for c in clients:
            assert (c.line(), c.line()) == ('Robotmode: RUNNING', 'Safetymode: NORMAL')
    finally:
        for c in clients:
            c.close()


def test_an_endless_line_closes_that_connection_only(port):
    dashboard, _ = port
    flood, other = Client(dashboard.address), Client(dashboard.address)
    try:
        assert flood.line() == WELCOME and other.line() == WELCOME
        flood.sock.sendall(b'x' * (MAX_LINE + 10))
        assert flood.closed()
        assert other.ask('robotmode') == 'Robotmode: RUNNING'
    finally:
        flood.close()
        other.close()


def test_an_address_in_use_is_refused_naming_it(port):
    dashboard, server = port
    host, number = dashboard.address
    with pytest.raises(PortError, match=f'cannot listen on {host}:{number}: '):
        DashboardPort(host, number, server, threading.Lock())


def test_the_port_and_the_ros_services_are_one_robot():
    with running_sim() as h:
        assert h.sim.dashboard_port is not None
        raw = h.client.create_client(RawRequest, '/dashboard_client/raw_request')
        mode = h.client.create_client(GetOperationalMode, '/dashboard_client/get_operational_mode')
        for service in (raw, mode):
            wait_still(service.service_is_ready, what='the dashboard services')
        client = Client(h.sim.dashboard_port.address)
        try:
            assert client.line() == WELCOME
            assert client.ask('PolyscopeVersion') == wait_answer(
                raw.call_async(RawRequest.Request(query='PolyscopeVersion'))).answer
            assert client.ask('set operational mode manual') == "Operational mode 'manual' is set"
            assert wait_answer(mode.call_async(GetOperationalMode.Request())).operational_mode.mode == 'MANUAL'
        finally:
            client.ask('set operational mode automatic')
            client.close()
