"""rclpy helpers for tests: private contexts, executors and spin-until-condition with deadlines."""
from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor


@contextmanager
def ros_context(ros_args: list[str] | None = None) -> Iterator[Context]:
    """A private rclpy Context, initialised (with `ros_args`, e.g. ['-p', 'node:name:=value']) and shut down around
    the block."""
    context = Context()
    rclpy.init(args=['--ros-args', *ros_args] if ros_args else None, context=context)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)


@contextmanager
def executor_with(context: Context, *nodes) -> Iterator[SingleThreadedExecutor]:
    """An executor on `context` with `nodes` added; nodes are destroyed afterwards."""
    executor = SingleThreadedExecutor(context=context)
    for node in nodes:
        executor.add_node(node)
    try:
        yield executor
    finally:
        executor.shutdown(timeout_sec=1.0)
        for node in nodes:
            node.destroy_node()


def spin_until(executor, condition: Callable[[], bool], timeout: float, what: str = 'condition') -> None:
    """Spin `executor` until `condition()` is true.

    Args:
        executor: an rclpy executor.
        condition: checked after every callback.
        timeout: deadline [s] of wall time.
        what: description used in the TimeoutError.

    Raises:
        TimeoutError: the deadline passed first.
    """
    deadline = time.monotonic() + timeout
    while not condition():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            raise TimeoutError(f'timed out after {timeout:.1f} s waiting for {what}')
        executor.spin_once(timeout_sec=min(0.05, remaining))


def spin_until_future(executor, future, timeout: float, what: str = 'future'):
    """Spin until `future` is done and return its result."""
    spin_until(executor, future.done, timeout, what)
    return future.result()
