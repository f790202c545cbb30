"""A TCP port of the robot: listening on an address, each connection served by a thread of its own."""
from __future__ import annotations

import socket
import socketserver
import threading
from collections.abc import Callable

from ur_sim_driver.errors import UrSimError


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
