"""A program's threads as the controller schedules them: the main program is thread 0, ``run name()`` starts
another; every control cycle (a "frame" of the URScript manual's thread scheduling) each runnable thread runs, in
the order the threads were started, until it spends robot time (a motion, ``sleep``, ``sync``, a blocking read,
``join``) or ends. A thread started in a cycle runs in that cycle, after the others.

``enter_critical`` keeps the other threads from running until the same thread's ``exit_critical`` (nested
sections count) while it runs; when it spends robot time inside the section (a motion, a blocking read), the others
run meanwhile, and it takes the section back when it goes on. The Client Library's External Control program relies
on it: its main thread waits for the next command in a blocking socket read inside a section, while its servo
thread commands the arm every cycle. ``kill`` ends a thread and the threads it started; its motion, if it commanded
the last one, goes on until another replaces it (a stop, say), as ur_rtde's ``speedStop`` relies on. A thread may
``join`` only a thread it started. When the main program ends, or a thread calls ``halt``, the program ends and
every thread with it.

Pure: the threads are generators of the interpreter that yield a :class:`~ur_sim_driver.urscript.values.Request`
whenever they need robot time; what a motion request does is the caller's (``program.py``).
"""
from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from typing import Any

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.urscript.values import PENDING, Request, ThreadHandle, is_number, show

SLEEP_TOLERANCE = 1e-9  # [s] a sleep this close to its end is over

# Given a thread and the robot request it made: a condition to wait for (the thread runs again once it holds), or
# None to go on at once.
Handler = Callable[['ScriptThread', Request], 'Callable[[], bool] | None']


@dataclass(eq=False)
class ScriptThread:
    """One thread: its generator, where it is (`line`, `column`, 1-based) and what it waits for."""

    name: str
    number: int  # 0: the main program
    parent: ScriptThread | None
    body: Generator[Request, Any, None] | None = None
    line: int = 0
    column: int = 0
    spinning: int = 0  # loop iterations since it last spent robot time
    reply: Any = None  # what the request it waits on returns to it
    sleep: float = 0.0  # [s] of robot time left to sleep
    synced: bool = False  # waits for the next cycle
    until: Callable[[], bool] | None = None  # runs again once this holds
    done: bool = False
    critical: int = 0  # depth of its enter_critical
    children: list[ScriptThread] = field(default_factory=list)

    @property
    def handle(self) -> ThreadHandle:
        return ThreadHandle(self.number, self.name)

    def runnable(self) -> bool:
        if self.done or self.sleep > 0.0 or self.synced:
            return False
        if self.until is not None:
            if not self.until():
                return False
            self.until = None
        return True


class Threads:
    """The threads of one program: the only owner of their list, of the critical section and of `current`, the
    thread running now (the interpreter reads it for scopes, lines and loop counts)."""

    def __init__(self) -> None:
        self.all: list[ScriptThread] = []
        self.current: ScriptThread | None = None
        self.critical: ScriptThread | None = None
        self.halted = False  # a thread called halt: the program ends
        self._numbers = 0

    @property
    def main(self) -> ScriptThread:
        return self.all[0]

    def start(self, name: str, body: Callable[[], Generator[Request, Any, None]]) -> ScriptThread:
        """A new thread running `body()`, started by the current thread (none: the main program)."""
        parent = self.current
        thread = ScriptThread(name, self._numbers, parent)
        self._numbers += 1
        thread.body = body()
        self.all.append(thread)
        if parent is not None:
            parent.children.append(thread)
        return thread

    def find(self, handle, what: str) -> ScriptThread | None:
        """The thread of `handle` (None when it has ended, or for a number: programs keep 0 in a handle's variable
        while no thread runs, and ur_rtde's script kills such variables as they are); ScriptError when `handle` is
        neither."""
        if is_number(handle):
            return None
        if not isinstance(handle, ThreadHandle):
            raise ScriptError(f'{what}: {show(handle)} is not a thread handle (what run returns)')
        return next((t for t in self.all if t.number == handle.number), None)

    def kill(self, thread: ScriptThread) -> None:
        """End `thread` and the threads it started, wherever they are."""
        for child in list(thread.children):
            self.kill(child)
        self._end(thread)
        if thread.body is not None and thread is not self.current:
            thread.body.close()

    def join(self, handle) -> Callable[[], bool] | None:
        """What the current thread waits for to join `handle`'s thread (None: it has ended already)."""
        target = self.find(handle, 'join')
        if target is None or target.done:
            return None
        if target.parent is not self.current:
            raise ScriptError(f'join: thread {target.name} was not started by this thread '
                              f'({self.current.name}); a thread can only join the threads it started')
        return lambda: target.done

    def enter_critical(self) -> None:
        self.current.critical += 1
        self.critical = self.current

    def exit_critical(self) -> None:
        thread = self.current
        if thread.critical == 0:
            raise ScriptError('exit_critical without enter_critical')
        thread.critical -= 1
        if thread.critical == 0:
            self.critical = None

    def new_cycle(self, period: float) -> None:
        """A control period [s] has passed: sleeps count down, a sync is over."""
        for thread in self.all:
            thread.sleep -= period
            if thread.sleep < SLEEP_TOLERANCE:  # 0.1 s is 50 periods of 0.002 s, whatever the rounding
                thread.sleep = 0.0
            thread.synced = False

    def step(self, handle: Handler) -> None:
        """Run each runnable thread until it waits (a ScriptError from any thread ends the step: the caller stops
        the program)."""
        k = 0
        while k < len(self.all) and not self.main.done and not self.halted:  # threads started now run now
            thread = self.all[k]
            k += 1
            if self.critical is None or self.critical is thread:
                self._advance(thread, handle)
        self.current = None
        if self.halted or self.main.done:
            for thread in self.all[1:]:
                if not thread.done:
                    self.kill(thread)

    def _advance(self, thread: ScriptThread, handle: Handler) -> None:
        while thread.runnable() and (self.critical is None or self.critical is thread) and not self.halted:
            self.current = thread
            if thread.critical:  # it goes on inside its section: the section is its again
                self.critical = thread
            try:
                request = thread.body.send(thread.reply)
            except StopIteration:
                self._end(thread)
                return
            finally:
                self.current = None
            thread.reply = None
            self.current = thread  # the handler's errors point at its line
            try:
                if request.kind == 'sleep':
                    thread.sleep = request.args[0]
                elif request.kind == 'sync':
                    thread.synced = True
                elif request.kind == 'join':
                    thread.until = request.args[0]
                elif request.kind == 'wait':
                    thread.until = _answer(thread, request.args[0])
                else:
                    thread.until = handle(thread, request)
            finally:
                self.current = None
            if thread.runnable():  # answered at once (a read of a closed socket): no robot time spent
                continue
            thread.spinning = 0  # it spends robot time: its loops count again
            if self.critical is thread:  # the others run meanwhile
                self.critical = None

    def _end(self, thread: ScriptThread) -> None:
        thread.done = True
        if self.critical is thread:
            self.critical = None
        thread.critical = 0
        thread.until = None


def _answer(thread: ScriptThread, poll: Callable[[], object]) -> Callable[[], bool]:
    """The condition of a wait: holds once `poll` answers, its answer then being what the call returns."""
    def ready() -> bool:
        value = poll()
        if value is PENDING:
            return False
        thread.reply = value
        return True
    return ready
