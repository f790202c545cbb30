"""RTDE on its TCP port (30004 on a UR): recipes set up, started and paused per connection, output data at the
robot's rate or a requested lower one, input data applied to the robot.

Per connection, as the RTDE guide describes the robot's side:

* ``V`` (request protocol version 1 or 2) is accepted; ``v`` answers the controller's software version;
* ``O`` sets up an output recipe (protocol 2: the frequency first, in (0, control rate]); the answer is a recipe id
  and each variable's type, ``NOT_FOUND`` for a name the simulated robot does not fill (the id is then 0: the recipe
  is not usable);
* ``I`` sets up an input recipe; a variable another connection's recipe holds answers ``IN_USE`` (id 0);
* ``S`` starts sending every output recipe, ``P`` pauses; ``U`` from the client writes its input recipe's values
  (``rtde_fields.write``); ``M`` from the client goes to the log.

Output data follows simulated time: the simulation loop calls :meth:`RtdePort.tick` after every control cycle and
each recipe is read on every k-th cycle (k = control rate / frequency), there and then, so that its timestamps are
exactly k periods apart; a sending thread per connection writes the packages out. A client that falls more than
``BACKLOG`` packages behind loses the oldest ones.
"""
from __future__ import annotations

import collections
import socket
import struct
import threading
from collections.abc import Callable
from dataclasses import dataclass

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.ports import rtde_protocol as rp
from ur_sim_driver.ports.rtde_fields import WRITABLE, CycleValues, served, write
from ur_sim_driver.ports.tcp_port import TcpPort

BACKLOG = 1000  # packages queued per connection
MAX_PACKAGE = 0xFFFF  # [bytes] a package's size field is 16 bits
MAX_RECIPES = 255  # per direction and connection: a recipe id is one byte


@dataclass(frozen=True)
class OutputRecipe:
    id: int
    names: tuple[str, ...]
    types: tuple[str, ...]
    every: int  # send on every this many control cycles
    format: struct.Struct


@dataclass(frozen=True)
class InputRecipe:
    id: int
    names: tuple[str, ...]
    types: tuple[str, ...]
    format: struct.Struct


class RtdePort:
    """RTDE listening on `address`:`port` (0: a free port), for the robot of `host`.

    Args:
        rate: the robot's control rate [Hz] (the highest output frequency).
        log: called with a line for the log (client text messages, refused inputs).
        values: the cycle's output variables, shared with the other ports that stream them (else its own).
    """

    def __init__(self, address: str, port: int, host: Host, rate: float,
                 log: Callable[[str], None] = lambda _: None, values: CycleValues | None = None) -> None:
        self.host, self.rate, self.log = host, rate, log
        self.values = values if values is not None else CycleValues(host)
        self._claims: dict[str, object] = {}  # input variable -> the session whose recipe holds it
        self._claims_lock = threading.Lock()
        self._sessions: list[_Session] = []  # started ones (replaced, never changed: the loop reads it unlocked)
        self._sessions_lock = threading.Lock()
        self._cycle = 0
        self._port = TcpPort('RTDE', address, port, lambda sock: _Session(self, sock).run())

    @property
    def address(self) -> tuple[str, int]:
        return self._port.address

    def tick(self) -> None:
        """After a control cycle (simulation loop, outside the lock): the recipes due now are read and queued."""
        sessions = self._sessions
        if not sessions:
            return
        self._cycle += 1
        cycle, values = self._cycle, self.values
        with self.host.lock:
            for session in sessions:
                due = [r for r in session.outputs if cycle % r.every == 0]
                if due:
                    session.queue(b''.join(session.data_package(r, [values[n] for n in r.names]) for r in due))

    @property
    def cycle(self) -> int:
        """Control cycles ticked while some connection streamed."""
        return self._cycle

    def streaming(self, session: _Session, on: bool) -> None:
        with self._sessions_lock:
            others = [s for s in self._sessions if s is not session]
            self._sessions = [*others, session] if on else others

    def claim(self, session: object, names: tuple[str, ...]) -> list[bool]:
        """Claim input variables for `session`: per name, whether another session holds it already."""
        with self._claims_lock:
            taken = [self._claims.get(n, session) is not session for n in names]
            if not any(taken):
                for n in names:
                    self._claims[n] = session
            return taken

    def release(self, session: object) -> None:
        with self._claims_lock:
            for name in [n for n, s in self._claims.items() if s is session]:
                del self._claims[name]

    def close(self) -> None:
        self._port.close()


class _Session:
    """One client connection."""

    def __init__(self, port: RtdePort, sock: socket.socket) -> None:
        self.port, self.sock = port, sock
        self.version = 1
        self.outputs: list[OutputRecipe] = []
        self.inputs: dict[int, InputRecipe] = {}
        self.started = False
        self.closed = False
        self.send_lock = threading.Lock()
        self._out: collections.deque[bytes] = collections.deque(maxlen=BACKLOG)
        self._ready = threading.Condition()
        self.sender: threading.Thread | None = None

    # ---- receiving ---------------------------------------------------------------------------
    def run(self) -> None:
        try:
            while True:
                header = self._read(rp.HEADER.size)
                if header is None:
                    return
                size, kind = rp.HEADER.unpack(header)
                if size < rp.HEADER.size:
                    return  # not RTDE: drop the connection
                payload = self._read(size - rp.HEADER.size) if size > rp.HEADER.size else b''
                if payload is None:
                    return
                self._handle(kind, payload)
        except (OSError, struct.error, ValueError, rp.ProtocolError):
            return
        finally:
            self.closed = True
            self._stop()
            self.port.release(self)

    def _read(self, n: int) -> bytes | None:
        data = b''
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                return None
            data += chunk
        return data

    def _send(self, data: bytes) -> None:
        with self.send_lock:
            self.sock.sendall(data)

    def _handle(self, kind: int, payload: bytes) -> None:
        if kind == rp.REQUEST_PROTOCOL_VERSION:
            (asked,) = struct.unpack('>H', payload[:2])
            accepted = asked in (1, 2)
            if accepted:
                self.version = asked
            self._send(rp.package(kind, bytes([int(accepted)])))
        elif kind == rp.GET_URCONTROL_VERSION:
            v = self.port.host.dashboard.version
            self._send(rp.package(kind, struct.pack('>IIII', v.major, v.minor, v.bugfix, v.build)))
        elif kind == rp.SETUP_OUTPUTS:
            self._setup_outputs(payload)
        elif kind == rp.SETUP_INPUTS:
            self._setup_inputs(payload)
        elif kind == rp.START:
            self._start()
        elif kind == rp.PAUSE:
            self._stop()
            self._send(rp.package(kind, b'\x01'))
        elif kind == rp.DATA_PACKAGE:
            self._input_data(payload)
        elif kind == rp.TEXT_MESSAGE:
            self.port.log(f'RTDE client message: {payload[1:1 + payload[0]].decode(errors="replace")}'
                          if payload else 'RTDE client message (empty)')
        else:
            raise rp.ProtocolError(f'unknown package type {kind}')

    def _setup_outputs(self, payload: bytes) -> None:
        frequency = self.port.rate
        if self.version >= 2:
            (frequency,) = struct.unpack('>d', payload[:8])
            payload = payload[8:]
        names = tuple(n for n in payload.decode().split(',') if n)
        version = self.port.host.dashboard.version
        types = tuple(rp.OUTPUTS[n] if n in rp.OUTPUTS and served(n, version) else rp.NOT_FOUND for n in names)
        refusal = None
        if names and rp.NOT_FOUND not in types:
            size = rp.HEADER.size + 1 + rp.recipe_format(types).size
            if not 0.0 < frequency <= self.port.rate:
                refusal = f'output frequency {frequency} Hz is outside (0, {self.port.rate:g}] Hz'
            elif size > MAX_PACKAGE:
                refusal = (f'output recipe of {len(names)} variables: its data package of {size} bytes is over '
                           f'the package limit of {MAX_PACKAGE} bytes')
            elif len(self.outputs) >= MAX_RECIPES:
                refusal = f'output recipe {len(self.outputs) + 1}: a connection has at most {MAX_RECIPES}'
        valid = bool(names) and rp.NOT_FOUND not in types and refusal is None
        recipe_id = len(self.outputs) + 1 if valid else 0
        if valid:
            every = max(1, round(self.port.rate / frequency))
            self.outputs.append(OutputRecipe(recipe_id, names, types, every, rp.recipe_format(types)))
        answer = ','.join(types).encode()
        self._send(rp.package(rp.SETUP_OUTPUTS, (bytes([recipe_id]) if self.version >= 2 else b'') + answer))
        if refusal is not None:  # after the answer: a client reads one package as the answer to its request
            self._send(rp.text_message(refusal, level=2))

    def _setup_inputs(self, payload: bytes) -> None:
        if len(self.inputs) >= MAX_RECIPES:
            self._send(rp.package(rp.SETUP_INPUTS, b'\x00'))
            self._send(rp.text_message(f'input recipe {len(self.inputs) + 1}: a connection has at most {MAX_RECIPES}',
                                       level=2))
            return
        names = tuple(n for n in payload.decode().split(',') if n)
        types = [rp.INPUTS[n] if n in rp.INPUTS and n in WRITABLE else rp.NOT_FOUND for n in names]
        if rp.NOT_FOUND not in types:
            taken = self.port.claim(self, names)
            types = [rp.IN_USE if t else kind for t, kind in zip(taken, types)]
        valid = bool(names) and rp.NOT_FOUND not in types and rp.IN_USE not in types
        recipe_id = max(self.inputs, default=0) + 1 if valid else 0
        if valid:
            self.inputs[recipe_id] = InputRecipe(recipe_id, names, tuple(types), rp.recipe_format(types))
        self._send(rp.package(rp.SETUP_INPUTS, bytes([recipe_id]) + ','.join(types).encode()))

    def _start(self) -> None:
        accepted = bool(self.outputs or self.inputs)
        self._send(rp.package(rp.START, bytes([int(accepted)])))
        if accepted and self.outputs and not self.started:
            self.started = True
            self.sender = threading.Thread(target=self._stream, name='rtde_session', daemon=True)
            self.sender.start()
            self.port.streaming(self, True)

    def _stop(self) -> None:
        self.port.streaming(self, False)
        self.started = False
        with self._ready:
            self._ready.notify_all()
        sender, self.sender = self.sender, None
        if sender is not None and sender is not threading.current_thread():
            sender.join(timeout=5.0)

    def _input_data(self, payload: bytes) -> None:
        recipe = self.inputs.get(payload[0]) if payload else None
        if recipe is None:
            self._send(rp.text_message(f'no input recipe {payload[0] if payload else "?"}', level=2))
            return
        flat = recipe.format.unpack(payload[1:1 + recipe.format.size])
        values = dict(zip(recipe.names, rp.regroup(flat, recipe.types)))
        with self.port.host.lock:
            refused = write(self.port.host, values)
        for line in refused:  # to ur_sim's log only: a client reading data packages takes any other as a failure
            self.port.log(f'RTDE input refused: {line}')

    # ---- sending -----------------------------------------------------------------------------
    def data_package(self, recipe: OutputRecipe, values: list) -> bytes:
        return rp.package(rp.DATA_PACKAGE, (bytes([recipe.id]) if self.version >= 2 else b'')
                          + recipe.format.pack(*rp.flatten(values)))

    def queue(self, data: bytes) -> None:
        """From the simulation loop: packages to send (the oldest go when the client is BACKLOG behind)."""
        with self._ready:
            self._out.append(data)
            self._ready.notify()

    def _stream(self) -> None:
        try:
            while self.started and not self.closed:
                with self._ready:
                    self._ready.wait_for(lambda: self._out or not self.started, 0.5)
                    batch = b''.join(self._out)
                    self._out.clear()
                if batch:
                    self._send(batch)
        except OSError:
            self.closed = True
