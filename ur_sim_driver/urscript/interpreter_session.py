"""Interpreter mode (PolyScope 5.10+): the robot's interpreter socket (TCP 30020) takes URScript statements, one line
each, while a program runs; a program that calls ``interpreter_mode()`` executes them, in order, in the scope it
called it from, until ``end_interpreter()``.

This module is the robot's side of it, pure (``ports/interpreter_port.py`` is the socket): each line is answered at
once with

* ``ack: <id>: <line>`` when it compiles and a program runs (the statements join the queue under that id), or
  ``discard: <reason>: <line>`` when it does not compile or no program runs;
* for the commands executed as soon as they come: ``skipbuffer`` drops the statements not executed yet (answer
  ``skipbuffer: <how many>``), ``abort`` stops the motion an interpreted or the main program's ``movej`` / ``movel``
  runs now (``abort: <1 if one was running, else 0>``), and the state commands ``statelastinterpreted``,
  ``statelastexecuted``, ``statelastcleared`` (an id) and ``stateunexecuted`` (a count), answered
  ``<command>: <number>``.

Ids count from 1 for the robot's life. One session per robot, owned by the program slot (``runner.py``); call it
under the simulation lock.
"""
from __future__ import annotations

from collections import deque

from lark import Tree

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.grammar import parse

STATE_COMMANDS = ('statelastinterpreted', 'statelastexecuted', 'statelastcleared', 'stateunexecuted')


class InterpreterSession:
    """The interpreter socket's queue and counters."""

    def __init__(self) -> None:
        self.queue: deque[tuple[int, list[Tree]]] = deque()
        self.active = False  # a program is inside interpreter_mode()
        self.ended = False  # end_interpreter() was called: interpreter_mode() returns
        self.abort_requested = False
        self.last_interpreted = 0
        self.last_executed = 0
        self.last_cleared = 0

    def handle(self, line: str, program_running: bool) -> str:
        """The answer to one line from the socket (without its end of line)."""
        text = line.strip()
        if text == 'skipbuffer':
            skipped = len(self.queue)
            self.queue.clear()
            return f'skipbuffer: {skipped}'
        if text == 'abort':
            self.abort_requested = self.active
            return f'abort: {int(self.active)}'
        if text in STATE_COMMANDS:
            value = {'statelastinterpreted': self.last_interpreted, 'statelastexecuted': self.last_executed,
                     'statelastcleared': self.last_cleared, 'stateunexecuted': len(self.queue)}[text]
            return f'{text}: {value}'
        if not program_running:
            return f'discard: Program not running: {text}'
        try:
            statements = list(parse(text).children)
        except ScriptError as exc:
            return f'discard: {exc}: {text}'
        if not statements:
            return f'discard: no statement: {text}'
        if any(_calls(s, 'interpreter_mode') for s in statements):
            return f'discard: interpreter_mode() cannot be called in interpreter mode (no nesting): {text}'
        self.last_interpreted += 1
        self.queue.append((self.last_interpreted, statements))
        return f'ack: {self.last_interpreted}: {text}'

    # ---- the program's side ----------------------------------------------------------------------------------
    def enter(self, clear_queue: bool) -> None:
        """interpreter_mode() begins (`clear_queue`: drop what came before, clearQueueOnEnter)."""
        if clear_queue:
            self.queue.clear()
        self.active, self.ended, self.abort_requested = True, False, False

    def next(self) -> tuple[int, list[Tree]] | None:
        """The next statements to execute (their id counts as executed from now), or None."""
        if not self.queue:
            return None
        item = self.queue.popleft()
        self.last_executed = item[0]
        return item

    def end(self) -> None:
        """end_interpreter(): interpreter_mode() returns once the statement running now is done."""
        self.ended = True

    def leave(self, clear: bool) -> None:
        """interpreter_mode() returned (`clear`: what it interpreted is cleared, clearOnEnd)."""
        if clear:
            self.clear()
        self.active, self.abort_requested = False, False

    def clear(self) -> None:
        """clear_interpreter(): what was interpreted so far counts as cleared."""
        self.last_cleared = self.last_executed

    def take_abort(self) -> bool:
        """Whether an abort came since the last call (the program stops its motion)."""
        abort, self.abort_requested = self.abort_requested, False
        return abort


def _calls(node, name: str) -> bool:
    if not isinstance(node, Tree):
        return False
    if node.data == 'call' and str(node.children[0]) == name:
        return True
    return any(_calls(c, name) for c in node.children)
