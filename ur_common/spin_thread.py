"""An rclpy executor spun by a background thread that can be stopped without a race.

rclpy Jazzy's ``Executor.shutdown()`` sets its shutdown flag and then skips its own wait for running work (the
check reads the flag it has just set), so it destroys the executor's guard condition while a ``spin()`` in another
thread may still be inside a wait. That thread then dies with ``'NoneType' object has no attribute 'handle'`` or
``InvalidHandle``. Here the thread's loop is told to stop and is joined first; the executor is shut down after.
"""
from __future__ import annotations

import io
import sys
import threading
import time
from collections.abc import Callable

from rclpy.executors import Executor, ExternalShutdownException
from rclpy.experimental import EventsExecutor

WAKE_PERIOD = 1.0  # [s] longest wait of one spin_once; stop() ends it at once with a guard condition
# [s] the same for rclpy's EventsExecutor, which takes no guard condition and whose wake() does not end a wait: its
# wait costs no wait set, so a short one is cheap, and stop() returns within it.
EVENTS_WAKE_PERIOD = 0.05


class SpinThread:
    """Spin `executor` in a daemon thread until stop(); `executor` is shut down by stop().

    Args:
        pace: when given, called after each callback; the thread then rests for the time it returns [s] (0: not
            at all). A subscriber to a simulation running many times faster than real time is never idle, and
            its thread would otherwise take half of the process's interpreter lock from the thread doing the work.
    """

    def __init__(self, executor: Executor, name: str = 'spin', pace: Callable[[], float] | None = None) -> None:
        self.executor = executor
        self._pace = pace
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._wake = None  # (node, guard condition) that stop() triggers

    def start(self) -> SpinThread:
        # rclpy's Executor.wake() only makes a waiting spin_once look again: with nothing to run it waits on until
        # its timeout (measured: stop() took the rest of WAKE_PERIOD, 0.5 s on average). A guard condition whose
        # callback runs ends that spin_once at once.
        nodes = self.executor.get_nodes()
        if nodes and isinstance(self.executor, Executor):  # rclpy's own executors (the EventsExecutor is not)
            self._wake = (nodes[0], nodes[0].create_guard_condition(lambda: None))
        self._thread.start()
        return self

    def _run(self) -> None:
        executor, context, pace = self.executor, self.executor.context, self._pace
        try:
            period = WAKE_PERIOD if isinstance(executor, Executor) else EVENTS_WAKE_PERIOD
            while not self._stop.is_set() and context.ok():
                executor.spin_once(timeout_sec=period)
                if pace is not None:
                    rest = pace()
                    if rest > 0.0:
                        self._stop.wait(rest)
        except ExternalShutdownException:
            pass  # the context went first: nothing left to spin
        except Exception:
            # Shut down between the loop's check and the executor's wait: rclpy raises RCLError ("the given context
            # is not valid") from the wait set instead of ExternalShutdownException. Nothing left to spin either.
            if context.ok():
                raise

    @property
    def running(self) -> bool:
        return self._thread.is_alive()

    def stop(self, timeout: float = 5.0) -> bool:
        """End the loop, join the thread, then shut the executor down; False if the thread did not end in time
        [s] (the executor is then left alone rather than destroyed under it)."""
        self._stop.set()
        if self._thread.is_alive():
            try:
                if self._wake is not None:
                    self._wake[1].trigger()
                else:
                    self.executor.wake()
            except Exception:  # noqa: BLE001 -- already shut down or destroyed: the loop ends on its own
                pass
            self._thread.join(timeout)
        if self._thread.is_alive():
            return False
        self._wait_for_pool(time.monotonic() + timeout)
        self.executor.shutdown(timeout_sec=timeout)
        if self._wake is not None:  # after the executor, which may still hold it among the entities it last saw
            node, guard = self._wake
            self._wake = None
            try:
                node.destroy_guard_condition(guard)
            except Exception:  # noqa: BLE001 -- the node was destroyed first, and its guard conditions with it
                pass
        return True

    def _wait_for_pool(self, deadline: float) -> None:
        """Until the callbacks that a MultiThreadedExecutor handed its thread pool (the guard's among them) have
        run, or `deadline` (monotonic [s]): its shutdown() skips that wait through the same flag as above, and a
        callback finishing after it fails on the executor's destroyed guard condition ("never retrieved")."""
        for task in list(getattr(self.executor, '_futures', ())):
            while not task.done() and time.monotonic() < deadline:
                time.sleep(0.001)  # a shutdown path: a callback's end has no event to wait on


def events_executor(context) -> Executor:
    """rclpy's EventsExecutor on `context`. Its factory enables faulthandler on ``sys.stderr``, which needs a file
    descriptor: where stderr has none (a capture such as pytest's capsys) the process's own stderr stands in for
    that moment."""
    stderr = sys.stderr
    try:
        stderr.fileno()
    except (AttributeError, ValueError, io.UnsupportedOperation):
        sys.stderr = sys.__stderr__
    try:
        return EventsExecutor(context=context)
    finally:
        sys.stderr = stderr
