"""The client sockets a URScript program opens (``socket_open`` and its family): named TCP connections from the
robot to a host and port, several at once, closed when the program ends, as the controller keeps them.

Nothing here blocks: a connection and every read are polled once a control cycle (and at once when asked), and
their timeouts count robot time (``now``), so a read blocks only the thread that waits on it, and a lockstep
simulation times out at the same simulated instant however slow the machine. The URScript functions and their
return values are in ``urscript/socket_functions.py``; this module owns the connections.

Outgoing connections go to loopback addresses only, unless `allow_remote` (the ``urscript.allow_remote_sockets``
parameter) lets a program reach other hosts: a simulator should not open connections into a plant's network on a
copied program's say-so.
"""
from __future__ import annotations

import errno
import ipaddress
import select
import socket
from collections.abc import Callable
from dataclasses import dataclass, field

from ur_sim_driver.urscript.values import PENDING

CONNECT_TIMEOUT = 2.0  # [s] of robot time: socket_open gives up after this, as the controller does
_CHUNK = 65536


@dataclass(eq=False)
class _Connection:
    sock: socket.socket
    connected: bool = False
    inbox: bytearray = field(default_factory=bytearray)
    outbox: bytearray = field(default_factory=bytearray)
    closed: bool = False  # the peer closed it, or it failed


class ScriptSockets:
    """The named sockets of one program. `now`: robot time [s]; `log`: where refusals are reported."""

    def __init__(self, now: Callable[[], float], log: Callable[[str], None], allow_remote: bool = False) -> None:
        self._now, self._log, self.allow_remote = now, log, allow_remote
        self._open: dict[str, _Connection] = {}

    # ---- connections ------------------------------------------------------------------------------------------
    def open(self, address: str, port: int, name: str) -> Callable[[], object]:
        """Start connecting `name` to address:port (an open socket of that name is closed first); a poll that
        returns PENDING, then True (connected) or False (refused, unreachable, not allowed, timed out)."""
        self.close(name)
        try:
            host = socket.gethostbyname(address)
        except OSError as exc:
            self._log(f'socket_open: {address!r} does not resolve ({exc})')
            return lambda: False
        if not self.allow_remote and not ipaddress.ip_address(host).is_loopback:
            self._log(f'socket_open: {address} is not a loopback address; ur_sim connects to other hosts only '
                      'with the parameter urscript.allow_remote_sockets true')
            return lambda: False
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        code = sock.connect_ex((host, port))
        connection = _Connection(sock)
        self._open[name] = connection
        deadline = self._now() + CONNECT_TIMEOUT

        def poll():
            if connection.closed:
                return False
            if code == 0 or connection.connected:
                connection.connected = True
                return True
            if code not in (errno.EINPROGRESS, errno.EWOULDBLOCK, errno.EAGAIN):
                return self._fail(name, connection, f'socket_open {address}:{port}: {errno.errorcode.get(code)}')
            _, writable, _ = select.select([], [sock], [], 0)
            if writable:
                error = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
                if error:
                    return self._fail(name, connection, f'socket_open {address}:{port}: {errno.errorcode.get(error)}')
                connection.connected = True
                return True
            if self._now() >= deadline:
                return self._fail(name, connection, f'socket_open {address}:{port}: no answer in {CONNECT_TIMEOUT} s')
            return PENDING
        return poll

    def close(self, name: str) -> None:
        connection = self._open.pop(name, None)
        if connection is not None:
            self._flush(connection)
            connection.sock.close()

    def close_all(self) -> None:
        """The program ended: every socket closes."""
        for name in list(self._open):
            self.close(name)

    def is_open(self, name: str) -> bool:
        connection = self._open.get(name)
        return connection is not None and connection.connected and not connection.closed

    # ---- data ----------------------------------------------------------------------------------------------------
    def send(self, name: str, data: bytes) -> bool:
        """Queue `data` on `name` and send what the network takes now; False when the socket is not open."""
        connection = self._open.get(name)
        if connection is None or not connection.connected or connection.closed:
            return False
        connection.outbox += data
        self._flush(connection)
        return not connection.closed

    def flush(self) -> None:
        """Once a cycle: send what waited for room."""
        for connection in self._open.values():
            if connection.connected and connection.outbox:
                self._flush(connection)

    def read(self, name: str, parse: Callable[[bytearray], tuple[int, object] | None], timeout: float,
             failure: object) -> Callable[[], object]:
        """A poll for a value read from `name`: `parse` takes the bytes received and returns (bytes used, value) or
        None while it needs more; `failure` when the socket is not open, is closed by the peer, or `timeout` [s]
        of robot time passes (<= 0: no timeout)."""
        deadline = self._now() + timeout if timeout > 0 else None

        def poll():
            connection = self._open.get(name)
            if connection is None or not connection.connected:
                return failure
            self._receive(connection)
            parsed = parse(connection.inbox)
            if parsed is not None:
                used, value = parsed
                del connection.inbox[:used]
                return value
            if connection.closed or (deadline is not None and self._now() >= deadline):
                return failure
            return PENDING
        return poll

    # ---- the network ---------------------------------------------------------------------------------------------
    def _receive(self, connection: _Connection) -> None:
        while not connection.closed:
            try:
                chunk = connection.sock.recv(_CHUNK)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                connection.closed = True
                return
            if not chunk:
                connection.closed = True
                return
            connection.inbox += chunk

    def _flush(self, connection: _Connection) -> None:
        while connection.outbox and not connection.closed:
            try:
                sent = connection.sock.send(connection.outbox)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                connection.closed = True
                return
            del connection.outbox[:sent]

    def _fail(self, name: str, connection: _Connection, why: str) -> bool:
        self._log(why)
        connection.closed = True
        if self._open.get(name) is connection:
            del self._open[name]
        connection.sock.close()
        return False
