"""The interpreter socket (TCP 30020 on an e-Series robot with PolyScope 5.10 or later): URScript statements, one
line each, for a program in ``interpreter_mode()``, answered one line each (``ack: ...``, ``discard: ...``, the
state commands; ``urscript/interpreter_session.py`` has the protocol). Several clients may be connected; each line
is handled under the simulation lock, in the order it arrives.

A CB3, an e-Series before 5.10 and PolyScope X have no interpreter socket: :class:`InterpreterPort` then refuses to
open, with :class:`PortError` saying so.
"""
from __future__ import annotations

import threading

from ur_sim_driver.ports.tcp_port import LinePort, PortError
from ur_sim_driver.robot.software import SoftwareVersion
from ur_sim_driver.urscript.runner import ScriptRunner

FIRST = (5, 10)  # the first PolyScope with interpreter mode


def has_interpreter_socket(version: SoftwareVersion) -> bool:
    return version.e_series and not version.polyscope_x and (version.major, version.minor) >= FIRST


class InterpreterPort(LinePort):
    """The interpreter socket on `host`:`port` (0: a free port chosen by the system), in front of `runner`'s
    interpreter session. Raises PortError when the address cannot be listened on or the software has no such
    socket."""

    def __init__(self, host: str, port: int, runner: ScriptRunner, lock: threading.Lock,
                 version: SoftwareVersion) -> None:
        if not has_interpreter_socket(version):
            raise PortError(f'interpreter socket: not on {host}:{port}, software {version.dotted()} has none '
                            '(PolyScope 5.10 or later on an e-Series robot)')
        self._runner, self._lock = runner, lock
        super().__init__('interpreter socket', host, port)

    def answer(self, line: str) -> tuple[str, bool]:
        with self._lock:
            return self._runner.interpreter.handle(line, self._runner.current is not None), False
