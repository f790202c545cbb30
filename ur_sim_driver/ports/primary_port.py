"""The primary, secondary and real-time interfaces on their TCP ports (30001, 30002 and 30003 on a UR): the robot's
state for every client, its messages for primary clients, and URScript from any, as a UR controller serves them.

Per primary or secondary connection: the version message first (``primary_messages.version_message``, the robot's
software version), then a ROBOT_STATE package every 100 ms of simulated time (RobotModeData, JointData,
CartesianInfo, KinematicsInfo, MasterboardData, ToolData and ConfigurationData). A real-time connection gets a
package every control cycle (``realtime_messages.py``: 500 Hz on e-Series, 125 Hz on CB3), from the first cycle
after it connects.
A primary client also gets the program slot's events as robot messages: KEY messages
``PROGRAM_XXX_STARTED`` / ``PROGRAM_XXX_STOPPED`` with the program's name, RUNTIME_EXCEPTION with the line and column,
and TEXT for a program's ``textmsg``.

Text from a client is URScript. A complete program (a ``def`` or ``sec`` block up to its ``end``, or a line of
bare statements) is submitted to the program slot (``urscript/runner.py``) under the simulation lock; one that does
not compile, or that the robot cannot run now, is answered with a RUNTIME_EXCEPTION to the port's primary clients and
nothing runs. The commands the client library sends the same way are carried out: ``power on``, ``power off``,
``set robotmode run`` (brake release), ``set unlock protective stop`` and ``stop program``.

The simulation loop calls :meth:`PrimaryPort.tick` after every control cycle and never waits for a client: each
connection has a sending thread and a queue of ``backlog`` packages, from which the oldest are dropped for a client
that does not read. Text that is not UTF-8, or a program longer than ``MAX_SCRIPT`` bytes, closes the connection.
TCP keepalive and a user timeout (``tcp_port.configure``) end a connection whose peer is gone (a half-open one) and
the threads with it.
"""
from __future__ import annotations

import collections
import math
import re
import socket
import threading
from collections.abc import Callable

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.errors import ScriptError
from ur_sim_driver.ports import primary_messages as pm
from ur_sim_driver.ports.realtime_messages import realtime_package
from ur_sim_driver.ports.rtde_fields import CycleValues
from ur_sim_driver.ports.tcp_port import TcpPort
from ur_sim_driver.robot.robot_state import RobotState
from ur_sim_driver.robot.software import SoftwareVersion, parse_version
from ur_sim_driver.urscript.runner import RUNTIME_ERROR, STARTED, STOPPED, TEXT, ScriptEvent

PRIMARY, SECONDARY, REALTIME = 'primary', 'secondary', 'real-time'
PERIOD = 0.1  # [s] of simulated time between robot state packages (10 Hz)
BACKLOG = 1000  # packages queued per connection
MAX_SCRIPT = 1024 * 1024  # [bytes] of one program (or one line) still incomplete
# Controller commands (not URScript) the client library sends as a script -> what they do to the robot.
COMMANDS: dict[str, Callable[[RobotState], str | None]] = {
    'power on': RobotState.power_on, 'power off': RobotState.power_off,
    'set robotmode run': RobotState.brake_release,
    'set unlock protective stop': RobotState.unlock_protective_stop, 'stop program': RobotState.stop,
}
_BLOCKS = frozenset(('def', 'sec', 'thread', 'if', 'while', 'for'))  # keywords whose line ending in ':' opens a block
_STRING = re.compile(r'"(?:[^"\\]|\\.)*"|\'(?:[^\'\\]|\\.)*\'')
_FIRST_WORD = re.compile(r'\s*([A-Za-z_]\w*)')


class ScriptAssembler:
    """Bytes from a client -> complete programs, in the order they arrived. A program is a ``def`` or ``sec`` block
    (or any block) up to the ``end`` that closes it, or one line of bare statements; blank and comment lines between
    programs are skipped.

    Raises (from :meth:`feed`):
        ValueError: text that is not UTF-8 (UnicodeDecodeError), or a program that grew over `limit` bytes.
    """

    def __init__(self, limit: int = MAX_SCRIPT) -> None:
        self.limit = limit
        self._partial: list[bytes] = []  # the line under way, in chunks (joined once its newline comes)
        self._partial_size = 0
        self._lines: list[str] = []  # the program under way
        self._size = 0
        self._depth = 0

    def feed(self, data: bytes) -> list[str]:
        """The programs `data` completes."""
        programs: list[str] = []
        if b'\n' in data:
            *lines, rest = b''.join((*self._partial, data)).split(b'\n')
            self._partial, self._partial_size = [rest], len(rest)
            for raw in lines:
                program = self._line(raw.decode('utf-8') + '\n')
                if program is not None:
                    programs.append(program)
        else:
            self._partial.append(data)
            self._partial_size += len(data)
        if self._size + self._partial_size > self.limit:
            raise ValueError(f'a program of more than {self.limit} bytes')
        return programs

    def _line(self, line: str) -> str | None:
        code = _STRING.sub('""', line).split('#', 1)[0].strip()
        if not self._lines and not code:
            return None
        self._lines.append(line)
        self._size += len(line)
        if self._size > self.limit:
            raise ValueError(f'a program of more than {self.limit} bytes')
        word = _FIRST_WORD.match(code)
        if word is not None and word.group(1) in _BLOCKS and code.endswith(':'):
            self._depth += 1
        elif word is not None and word.group(1) == 'end':
            self._depth -= 1
        if self._depth > 0:
            return None
        program, self._lines, self._size, self._depth = ''.join(self._lines), [], 0, 0
        return program


def software_version(host: Host) -> SoftwareVersion:
    """The robot's software version (``cfg.software_version``, resolved or as given)."""
    version = host.cfg.software_version
    return parse_version(version, host.cfg.simulated_ur_type) if isinstance(version, str) else version


class PrimaryPort:
    """The primary interface (or the secondary or real-time one) on `address`:`port` (0: a free port), for the robot
    of `host`.

    Args:
        kind: PRIMARY; SECONDARY: robot state only, no robot messages after the version message; REALTIME: the
            real-time package every control cycle, no version message and no robot messages. URScript is run from
            every kind.
        backlog: packages queued per connection before the oldest are dropped.
        log: called with a line for the log (programs refused, connections closed for bad input).

    Raises:
        PortError: the address cannot be listened on.
    """

    def __init__(self, address: str, port: int, host: Host, kind: str = PRIMARY, backlog: int = BACKLOG,
                 log: Callable[[str], None] = lambda _: None, values: CycleValues | None = None) -> None:
        if kind not in (PRIMARY, SECONDARY, REALTIME):
            raise ValueError(f'interface kind {kind!r}: one of {PRIMARY!r}, {SECONDARY!r}, {REALTIME!r}')
        self.host, self.kind, self.backlog, self.log = host, kind, backlog, log
        self.values = values if values is not None else CycleValues(host)  # the real-time package's
        self.what = f'{kind} interface'
        self.version = software_version(host)
        params = host.sim.params
        self._kinematics = pm.kinematics_info(params)
        self._configuration = pm.configuration_data(params, self.version)
        self._clients: list[_Client] = []  # replaced, never changed: the loop reads it unlocked
        self._clients_lock = threading.Lock()
        self._next = 0  # index of the next 100 ms period whose state is due
        self._unlisten: Callable[[], None] | None = None
        if kind == PRIMARY and host.scripts is not None:
            with host.lock:
                self._unlisten = host.scripts.listen(self._on_event)
        self._port = TcpPort(self.what, address, port, lambda sock: _Client(self, sock).run())

    @property
    def address(self) -> tuple[str, int]:
        return self._port.address

    @property
    def clients(self) -> int:
        """Connections open now."""
        return len(self._clients)

    @property
    def queued(self) -> list[int]:
        """Packages waiting to be sent, per connection."""
        return [len(c.out) for c in self._clients]

    def tick(self) -> None:
        """After a control cycle (simulation loop, outside the lock): the robot state is queued for every client
        when a new 100 ms period of simulated time has begun (real-time: every cycle)."""
        if self.kind == REALTIME:
            clients = self._clients
            if clients:
                with self.host.lock:
                    package = realtime_package(self.values, self.version)
                for client in clients:
                    client.queue(package)
            return
        period = math.floor(self.host.sim.time / PERIOD + 1e-6)
        if period < self._next:
            return
        self._next = period + 1
        clients = self._clients
        if clients:
            with self.host.lock:
                state = pm.robot_state_now(self.host, self.version, self._kinematics, self._configuration)
            for client in clients:
                client.queue(state)

    def close(self) -> None:
        """Stop listening, stop forwarding the program slot's events and close every connection."""
        if self._unlisten is not None:
            with self.host.lock:
                self._unlisten()
        self._port.close()
        for client in self._clients:
            client.close()

    # ---- for the connections ---------------------------------------------------------------------------------
    def attach(self, client: _Client, on: bool) -> None:
        with self._clients_lock:
            others = [c for c in self._clients if c is not client]
            self._clients = [*others, client] if on else others

    def execute(self, text: str) -> None:
        """Run a complete program (or carry out a controller command) from a client."""
        command = COMMANDS.get(' '.join(text.split()).lower())
        if command is not None:
            with self.host.lock:
                refusal = command(self.host.robot)
            if refusal:
                self.log(f'{self.what}: {text.strip()!r} refused: {refusal}')
            return
        if self.host.scripts is None:
            self.log(f'{self.what}: no program slot; program ignored')
            return
        try:
            program = self.host.scripts.compile(text)  # outside the lock: parsing takes time
            with self.host.lock:
                self.host.scripts.start(program)
        except ScriptError as exc:
            self.log(f'{self.what}: program refused: {exc}')
            with self.host.lock:  # the lock the loop's events come under: one order of messages for the clients
                self._on_event(ScriptEvent(RUNTIME_ERROR, '', str(exc), exc.line, exc.column))

    def _on_event(self, event: ScriptEvent) -> None:
        """Under the simulation lock: a program slot event as a robot message to every primary client."""
        if self.kind != PRIMARY:
            return
        t = self.host.sim.time
        if event.kind in (STARTED, STOPPED):
            data = pm.key_message(pm.PROGRAM_STARTED if event.kind == STARTED else pm.PROGRAM_STOPPED, event.name, t)
        elif event.kind == RUNTIME_ERROR:
            data = pm.runtime_exception(event.line, event.column, event.text, t)
        elif event.kind == TEXT:
            data = pm.text_message(event.text, t)
        else:
            return
        for client in self._clients:
            client.queue(data)


class _Client:
    """One connection: this thread reads and runs programs, a sending thread writes the queue out."""

    def __init__(self, port: PrimaryPort, sock: socket.socket) -> None:
        self.port, self.sock = port, sock
        self.out: collections.deque[bytes] = collections.deque(maxlen=port.backlog)
        self._ready = threading.Condition()
        self.closed = False

    def run(self) -> None:
        sender = threading.Thread(target=self._send, name=self.port.what.replace(' ', '_') + '_sender', daemon=True)
        try:
            if self.port.kind != REALTIME:
                with self.port.host.lock:
                    version = pm.version_message(self.port.version, self.port.host.sim.time)
                self.queue(version)
            self.port.attach(self, True)
            sender.start()
            self._receive()
        except (OSError, ValueError) as exc:
            if not self.closed:
                self.port.log(f'{self.port.what}: connection closed: {exc}')
        finally:
            self.port.attach(self, False)
            self.close()
            if sender.ident is not None:
                sender.join(timeout=5.0)

    def _receive(self) -> None:
        assembler = ScriptAssembler()
        while not self.closed:
            data = self.sock.recv(65536)
            if not data:
                return
            for program in assembler.feed(data):
                self.port.execute(program)

    def queue(self, data: bytes) -> None:
        """Data to send (the oldest package goes when `backlog` are waiting)."""
        with self._ready:
            if not self.closed:
                self.out.append(data)
                self._ready.notify()

    def close(self) -> None:
        """End the connection: both threads return."""
        with self._ready:
            self.closed = True
            self.out.clear()
            self._ready.notify_all()
        try:
            self.sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass  # closed already

    def _send(self) -> None:
        while True:
            with self._ready:
                self._ready.wait_for(lambda: self.out or self.closed)
                if self.closed:
                    return
                batch = b''.join(self.out)
                self.out.clear()
            try:
                self.sock.sendall(batch)
            except OSError:
                self.close()
                return
