"""URScript's socket functions against a loopback server written here (no ROS): the program connects, sends lines,
integers and bytes, reads them back in every form with the manual's return values, a read blocks only its own
thread, timeouts count robot time, and refused, remote and unknown sockets fail as the controller's do.

The server runs in the test's own thread, polled before each control cycle, so the program and the server take turns
as the simulated robot steps; reads that must succeed wait without a timeout, so the outcome does not depend on
when the loopback delivers."""
from __future__ import annotations

import socket
import struct

import pytest
from script_box import COUNTER, Box

from ur_sim_driver.ports.script_sockets import ScriptSockets


class Server:
    """A loopback server answering the program's requests: 'hello' (after `delay` cycles), an integer, GET/SET."""

    def __init__(self, delay: int = 0) -> None:
        self.listener = socket.create_server(('127.0.0.1', 0))
        self.listener.setblocking(False)
        self.port = self.listener.getsockname()[1]
        self.peer: socket.socket | None = None
        self.inbox = b''
        self.delay, self.steps, self.due = delay, 0, None
        self.received: list[bytes] = []

    def poll(self) -> None:
        self.steps += 1
        if self.peer is None:
            try:
                self.peer, _ = self.listener.accept()
                self.peer.setblocking(False)
            except BlockingIOError:
                return
        try:
            self.inbox += self.peer.recv(4096)
        except BlockingIOError:
            pass
        if self.inbox.startswith(b'hello\n'):
            self.inbox = self.inbox[6:]
            self.received.append(b'hello')
            self.due = self.steps + self.delay
        if self.due is not None and self.steps >= self.due:
            self.due = None
            self.peer.sendall(b'world\r\n')
        if len(self.inbox) >= 4 and not self.inbox[:1].isalpha():
            (value,) = struct.unpack('>i', self.inbox[:4])
            self.inbox = self.inbox[4:]
            self.received.append(value)
            self.peer.sendall(struct.pack('>ii', 2 * value, 42) + b'noise(1.5, -2, 3e-1)' + bytes([7, 255]) +
                              b'xx<in\\tside>')
        for line in (b'GET X\n', b'SET Y 12\n'):
            if self.inbox.startswith(line):
                self.inbox = self.inbox[len(line):]
                self.received.append(line.strip())
                if line.startswith(b'GET'):
                    self.peer.sendall(b'X 99\n')

    def close(self) -> None:
        if self.peer is not None:
            self.peer.close()
        self.listener.close()


@pytest.fixture
def server():
    s = Server(delay=25)
    yield s
    s.close()


def test_a_program_talks_to_a_loopback_server_in_every_form(server):
    box = Box(before_step=server.poll)
    box.run('def prog():\n' + COUNTER + f'''  textmsg("open ", socket_open("127.0.0.1", {server.port}, "a"))
  run counter()
  socket_send_line("hello", "a")
  before = ticks
  textmsg(socket_read_line("a", timeout=0))
  textmsg("waited ", ticks - before >= 25)
  socket_send_int(-7, "a")
  textmsg(socket_read_binary_integer(2, "a", 0))
  textmsg(socket_read_ascii_float(3, "a", 0))
  textmsg(socket_read_byte_list(2, "a", 0))
  textmsg(socket_read_string("a", prefix="<", suffix=">", interpret_escape=True, timeout=0))
  textmsg(socket_get_var("X", "a"))
  socket_set_var("Y", 12, "a")
  textmsg(socket_read_binary_integer(1, "a", 0.5))
  socket_close("a")
  textmsg(socket_send_line("after close", "a"))
  textmsg(socket_read_line("a"))
end''')
    assert not box.errors(), box.errors()
    assert box.log == ['open True', 'world', 'waited True', '[2, -14, 42]', '[3, 1.5, -2, 0.3]', '[2, 7, 255]',
                       'in\tside', '99', '[0, -1]', 'False', '']
    assert server.received == [b'hello', -7, b'GET X', b'SET Y 12']


def test_a_read_times_out_in_robot_time(server):
    box = Box(before_step=server.poll)
    took = box.run(f'''def prog():
  socket_open("127.0.0.1", {server.port})
  textmsg(socket_read_ascii_float(2, timeout=0.3))
  textmsg(socket_read_string(timeout=0.1) == "")
end''')
    assert box.log == ['[0, -1, -1]', 'True']
    assert took == pytest.approx(0.4, abs=0.01)


def test_refused_remote_and_unknown_sockets_fail_without_stopping_the_program():
    closed = socket.create_server(('127.0.0.1', 0))
    port = closed.getsockname()[1]
    closed.close()  # nothing listens there now
    box = Box()
    box.run(f'''def prog():
  textmsg(socket_open("127.0.0.1", {port}, "refused"))
  textmsg(socket_open("192.0.2.1", 80, "remote"))
  textmsg(socket_send_string("x", "nobody"))
  textmsg(socket_read_byte_list(1, "nobody"))
end''')
    assert box.log == ['False', 'False', 'False', '[0, -1]']
    assert any('ECONNREFUSED' in m for m in box.network_log)
    assert any('not a loopback address' in m and 'allow_remote_sockets' in m for m in box.network_log)


def test_bad_arguments_are_runtime_errors_that_name_them():
    for source, reason in [
        ('socket_open("127.0.0.1", 70000)', 'socket_open: port is an integer in [1, 65535]; got 70000'),
        ('socket_read_binary_integer(31)', 'number is an integer in [1, 30]; got 31'),
        ('socket_send_byte(256)', 'socket_send_byte: value is an integer in [0, 255]; got 256'),
        ('socket_read_line(3)', 'socket_read_line: socket_name is a string; got 3'),
    ]:
        box = Box()
        box.run(f'def prog():\n  {source}\nend')
        (error,) = box.errors()
        assert error.line == 2 and reason in error.text, error


def test_the_sockets_of_a_program_close_when_it_ends(server):
    sockets = []

    def make():
        sockets.append(ScriptSockets(lambda: 0.0, print))
        return sockets[-1]
    box = Box(before_step=server.poll)
    box.runner._sockets = make  # to look at them after the program
    box.run(f'def prog():\n  socket_open("127.0.0.1", {server.port}, "kept")\nend')
    assert not sockets[0].is_open('kept')


def test_a_loop_reading_a_socket_its_peer_closed_is_an_infinite_loop_not_a_hung_cycle(server):
    """The failed read answers at once and spends no robot time, so a thread that reads in a loop without sync
    never gives the cycle back: the controller's infinite loop error, as for any such loop (the Client Library's
    script command thread does so once the driver is gone)."""
    box = Box(before_step=server.poll)
    box.runner.submit(f'''def prog():
  socket_open("127.0.0.1", {server.port}, "c")
  sync()
  while True:
    data = socket_read_binary_integer(1, "c", 0)
  end
end''')
    for _ in range(10):
        box.step()
    assert server.peer is not None and box.runner.current is not None  # it waits for data, a cycle at a time
    server.peer.close()
    server.peer = None
    box.step()  # one cycle, and its end: the program stops with the error
    (error,) = box.errors()
    assert 'infinite loop detected' in error.text and error.line == 4  # the while
    assert box.runner.current is None
