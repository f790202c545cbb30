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
from collections.abc import Callable

from rclpy.executors import Executor, ExternalShutdownException
from rclpy.experimental import EventsExecutor

WAKE_PERIOD = 1.0  # [s] longest wait of one spin_once; stop() wakes the executor at once anyway


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

    def start(self) -> SpinThread:
        self._thread.start()
        return self

    def _run(self) -> None:
        executor, context, pace = self.executor, self.executor.context, self._pace
        try:
            while not self._stop.is_set() and context.ok():
                executor.spin_once(timeout_sec=WAKE_PERIOD)
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
                self.executor.wake()
            except Exception:  # noqa: BLE001 -- already shut down: the loop ends on its own
                pass
            self._thread.join(timeout)
        if self._thread.is_alive():
            return False
        self.executor.shutdown(timeout_sec=timeout)
        return True


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
