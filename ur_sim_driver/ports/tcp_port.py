"""A TCP port of the robot: listening on an address, each connection served by a thread of its own, its socket
configured so that a peer that is gone (a half-open connection) ends it: TCP keepalive probes and a user timeout."""
from __future__ import annotations

import socket
import socketserver
import threading
from collections.abc import Callable

from ur_sim_driver.errors import UrSimError

SEND_BUFFER = 64 * 1024  # [bytes] the kernel's send buffer per connection
KEEPALIVE = (30, 10, 3)  # idle [s], interval [s] and count of TCP keepalive probes
USER_TIMEOUT = 30_000  # [ms] unacknowledged data after which the kernel ends a connection


class PortError(UrSimError):
    """A port could not be opened (address in use, not permitted, unknown host)."""


class TcpPort:
    """Listens on `host`:`port` (0: a free port chosen by the system) and calls `serve(connection)` for each client
    in a thread of its own; the connection is closed when `serve` returns.

    Raises:
        PortError: the address cannot be listened on; the message names `what`, the address and the reason.
    """

    def __init__(self, what: str, host: str, port: int, serve: Callable[[socket.socket], None]) -> None:
        class Handler(socketserver.BaseRequestHandler):
            def handle(self) -> None:
                configure(self.request)
                serve(self.request)

        try:
            self._tcp = socketserver.ThreadingTCPServer((host, port), Handler, bind_and_activate=False)
            self._tcp.daemon_threads = True  # a client still connected at shutdown does not hold the process
            self._tcp.allow_reuse_address = True  # restart at once after a stop, as a robot's server comes back
            self._tcp.server_bind()
            self._tcp.server_activate()
        except OSError as exc:
            raise PortError(f'{what}: cannot listen on {host}:{port}: {exc.strerror or exc}') from None
        self._thread = threading.Thread(target=self._tcp.serve_forever, kwargs={'poll_interval': 0.1},
                                        name=what.replace(' ', '_'), daemon=True)
        self._thread.start()

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) listened on."""
        host, port = self._tcp.server_address[:2]
        return str(host), int(port)

    def close(self) -> None:
        """Stop listening and wait for the listening thread (connections still open end with the process)."""
        self._tcp.shutdown()
        self._tcp.server_close()
        self._thread.join(timeout=5.0)


MAX_LINE = 64 * 1024  # [bytes] a longer line closes a line server's connection


def serve_lines(connection: socket.socket, answer: Callable[[str], tuple[str, bool]], greeting: str = '') -> None:
    """A line protocol: the greeting (if any), then one answer line per line received (`answer(line)`: the answer,
    and whether to close after it). Lines end with ``\\n`` (a ``\\r`` before it is dropped); a line longer than
    MAX_LINE bytes closes the connection, so that a client that never sends a newline cannot hold memory."""
    with connection.makefile('rb') as rfile:
        if greeting:
            connection.sendall((greeting + '\n').encode())
        while True:
            raw = rfile.readline(MAX_LINE + 1)
            if not raw or (len(raw) > MAX_LINE and not raw.endswith(b'\n')):
                return  # the client closed the connection, or sent an endless line
            reply, close = answer(raw.decode('utf-8', errors='replace').rstrip('\n').rstrip('\r'))
            connection.sendall((reply + '\n').encode())
            if close:
                return


class LinePort:
    """A line protocol on a TcpPort (:func:`serve_lines`): a subclass answers each line (:meth:`answer`)."""

    def __init__(self, what: str, host: str, port: int, greeting: str = '') -> None:
        self._port = TcpPort(what, host, port, lambda connection: serve_lines(connection, self.answer, greeting))

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) listened on."""
        return self._port.address

    def close(self) -> None:
        self._port.close()

    def answer(self, line: str) -> tuple[str, bool]:
        """The answer to `line`, and whether to close the connection after it."""
        raise NotImplementedError


def close_all(ports: list) -> None:
    """Close `ports` (the robot's ports, each built on a TcpPort) side by side: each waits up to its poll interval
    (0.1 s) for its listening thread to notice."""
    closers = [threading.Thread(target=port.close, name='close_port') for port in ports]
    for closer in closers:
        closer.start()
    for closer in closers:
        closer.join()


def configure(sock: socket.socket) -> None:
    """A bounded send buffer, no Nagle delay (a package per send), keepalive probes and a user timeout (where the
    system has them)."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    for name, value in zip(('TCP_KEEPIDLE', 'TCP_KEEPINTVL', 'TCP_KEEPCNT'), KEEPALIVE):
        if hasattr(socket, name):
            sock.setsockopt(socket.IPPROTO_TCP, getattr(socket, name), value)
    if hasattr(socket, 'TCP_USER_TIMEOUT'):
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_USER_TIMEOUT, USER_TIMEOUT)
