"""Interpreter mode: statements for a program in ``interpreter_mode()``, one line each, answered with ack or discard,
executed in order in the program's scope; the state commands, skipbuffer, abort of a move, end_interpreter. First
on the simulated robot stepped cycle by cycle (the session's lines handed in between cycles, no ROS), then over the
interpreter socket (TCP) of a running ur_sim."""
from __future__ import annotations

import socket

import numpy as np
import pytest
from script_box import READY, Box
from sim_harness import running_sim, wait_for

from ur_sim_driver.ports.interpreter_port import InterpreterPort
from ur_sim_driver.ports.tcp_port import PortError
from ur_sim_driver.robot.software import SoftwareVersion

PROGRAM = '''def prog():
  x = 1
  textmsg("before")
  interpreter_mode()
  textmsg("after ", x)
end'''


def _steps(box: Box, n: int) -> None:
    for _ in range(n):
        box.step()


def test_statements_run_in_the_programs_scope_in_order_until_end_interpreter():
    box = Box()
    session = box.runner.interpreter
    assert session.handle('textmsg("early")', False) == 'discard: Program not running: textmsg("early")'
    box.runner.submit(PROGRAM)
    _steps(box, 3)
    assert box.log == ['before'] and session.active
    assert session.handle('x = x + 41', True) == 'ack: 1: x = x + 41'
    assert session.handle('def twice(v): return 2 * v end textmsg(twice(x))', True).startswith('ack: 2: ')
    assert session.handle('movej([0, 0', True).startswith("discard: syntax error on line 1, column 12: unexpected")
    assert session.handle('statelastinterpreted', True) == 'statelastinterpreted: 2'
    assert session.handle('stateunexecuted', True) == 'stateunexecuted: 2'
    _steps(box, 3)
    assert box.log == ['before', '84']
    assert session.handle('statelastexecuted', True) == 'statelastexecuted: 2'
    assert session.handle('interpreter_mode()', True).startswith('discard: interpreter_mode() cannot be called')
    assert session.handle('end_interpreter()', True) == 'ack: 3: end_interpreter()'
    _steps(box, 3)
    assert box.log == ['before', '84', 'after 42'] and box.runner.current is None
    assert session.handle('statelastcleared', True) == 'statelastcleared: 3'
    assert not box.errors()


def test_skipbuffer_drops_what_waits_and_abort_stops_the_move():
    box = Box()
    session = box.runner.interpreter
    box.runner.submit(PROGRAM)
    _steps(box, 3)
    far = [float(v) for v in np.add(READY, [1.5, 0, 0, 0, 0, 0])]
    assert session.handle(f'movej({far}, a=1.0, v=0.5)', True).startswith('ack: 1')
    assert session.handle('textmsg("skipped")', True).startswith('ack: 2')
    _steps(box, 250)  # half a second into the move
    assert session.handle('skipbuffer', True) == 'skipbuffer: 1'
    assert session.handle('abort', True) == 'abort: 1'
    _steps(box, 500)
    q = box.sim.state().q
    assert READY[0] + 0.05 < q[0] < far[0] - 0.5 and abs(box.sim.state().qd[0]) < 1e-3  # stopped part way
    assert 'skipped' not in box.log and box.runner.current is not None  # still in interpreter mode
    session.handle('end_interpreter()', True)
    _steps(box, 3)
    assert box.runner.current is None and not box.errors()


def test_interpreter_mode_only_in_the_main_thread():
    box = Box()
    box.run('def prog():\n  thread t():\n    interpreter_mode()\n  end\n  run t()\n  sleep(0.1)\nend')
    assert 'only be called in the main thread' in box.errors()[0].text


def test_a_cb3_and_old_software_have_no_interpreter_socket():
    box = Box()
    for version in (SoftwareVersion(3, 15, 8, 0), SoftwareVersion(5, 9, 4, 0), SoftwareVersion(10, 7, 0, 0)):
        with pytest.raises(PortError, match='has none'):
            InterpreterPort('127.0.0.1', 0, box.runner, None, version)


class LineClient:
    def __init__(self, address) -> None:
        self.sock = socket.create_connection(address, timeout=30)
        self.file = self.sock.makefile('rb')

    def ask(self, line: str) -> str:
        self.sock.sendall((line + '\n').encode())
        return self.file.readline().decode().rstrip('\n')

    def close(self) -> None:
        self.file.close()
        self.sock.close()


def test_over_the_interpreter_socket_of_a_running_ur_sim():
    with running_sim() as h:
        port = h.sim.interpreter_port
        assert port is not None
        client = LineClient(port.address)
        try:
            assert client.ask('textmsg("x")') == 'discard: Program not running: textmsg("x")'
            with h.sim.host.lock:
                h.sim.host.scripts.submit('def prog():\n  interpreter_mode()\n  set_standard_digital_out(3, '
                                          'True)\nend')
            wait_for(lambda: h.sim.host.scripts.interpreter.active, what='interpreter mode')
            assert client.ask('set_standard_digital_out(2, True)') == 'ack: 1: set_standard_digital_out(2, True)'
            wait_for(lambda: h.sim.sim.io.digital_out[2] == 1.0, what='digital out 2 set by the statement')
            assert client.ask('statelastexecuted') == 'statelastexecuted: 1'
            assert client.ask('end_interpreter()') == 'ack: 2: end_interpreter()'
            wait_for(lambda: h.sim.host.scripts.current is None, what='the program to end')
            assert h.sim.sim.io.digital_out[3] == 1.0  # the program went on after interpreter mode
        finally:
            client.close()
            with h.sim.host.lock:
                h.sim.sim.io = h.sim.sim.io.with_digital_out(2, 0.0).with_digital_out(3, 0.0)
