"""The dashboard server on its TCP port (29999 on a UR), in front of the robot's one command interpreter.

A UR controller's dashboard server greets each connection with ``Connected: Universal Robots Dashboard Server``,
then answers every command line with one line; ``quit`` answers ``Disconnected`` and closes the connection (as
does ``shutdown``, after ``Shutting down``). Several clients may be connected at once, each answered in its own
order. The answers come from :class:`~ur_sim_driver.robot.dashboard_server.DashboardServer`, the same instance the
ROS ``/dashboard_client`` services use, so a popup opened over TCP, a program loaded through ROS or a user role set
either way is one robot's state. Each command is handled under the simulation lock, as the services handle theirs.

Lines end with ``\\n`` (a ``\\r`` before it is dropped); a line longer than ``tcp_port.MAX_LINE`` bytes closes the
connection, so that a client that never sends a newline cannot hold memory (``tcp_port.serve_lines``).

A PolyScope X robot (software 10.x) has no dashboard server: its Robot API (HTTP) replaces it, and nothing listens
on port 29999 (URSim's start script does not even forward the port for PolyScope X). :class:`DashboardPort` then
refuses to open, with :class:`PortError` saying so.
"""
from __future__ import annotations

import threading
from collections.abc import Callable

from ur_sim_driver.ports.tcp_port import LinePort, PortError
from ur_sim_driver.robot.dashboard_server import DashboardServer

WELCOME = 'Connected: Universal Robots Dashboard Server'
CLOSING = ('quit', 'shutdown')  # commands after whose answer the server closes the connection


class DashboardPort(LinePort):
    """The dashboard server listening on `host`:`port` (0: a free port chosen by the system).

    Args:
        server: the robot's command interpreter.
        lock: the simulation lock, held while a command is handled.
        log: called with a line for the log when a command is refused (the reason, which the answer does not give).

    Raises:
        PortError: the address cannot be listened on, or the robot runs PolyScope X (no dashboard server).
    """

    def __init__(self, host: str, port: int, server: DashboardServer, lock: threading.Lock,
                 log: Callable[[str], None] = lambda _: None) -> None:
        if server.version.polyscope_x:
            raise PortError(f'dashboard server: not on {host}:{port}, PolyScope X {server.version.dotted()} has none '
                            '(its Robot API replaces it)')
        self._server, self._lock, self._log = server, lock, log
        super().__init__('dashboard server', host, port, WELCOME)

    def answer(self, line: str) -> tuple[str, bool]:
        with self._lock:
            reply = self._server.handle(line)
        if reply.refusal:
            self._log(f"dashboard port '{line}': {reply.answer} ({reply.refusal})")
        return reply.answer, ' '.join(line.lower().split()) in CLOSING
