"""SpinThread: callbacks run while it spins, and stop() ends the thread before the executor is destroyed."""
import threading
import time

import pytest
from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from ros_helpers import ros_context
from sim_harness import wait_for
from std_msgs.msg import Int32

from ur_common import spin_thread
from ur_common.spin_thread import SpinThread

# An exception in the spin thread (the race this class exists to avoid) fails the test.
pytestmark = pytest.mark.filterwarnings('error::pytest.PytestUnhandledThreadExceptionWarning')


def _pub_sub(ctx, executor_cls):
    received = []
    got = threading.Event()
    node = Node('spin_thread_test', context=ctx)
    pub = node.create_publisher(Int32, 'spin_thread_topic', 10)

    def on_msg(msg):
        received.append(msg.data)
        got.set()
    node.create_subscription(Int32, 'spin_thread_topic', on_msg, 10)
    executor = executor_cls(context=ctx)
    executor.add_node(node)
    return node, pub, executor, received, got


@pytest.mark.parametrize('executor_cls', [SingleThreadedExecutor, MultiThreadedExecutor])
def test_callbacks_run_and_stop_joins_before_shutdown(executor_cls):
    with ros_context() as ctx:
        node, pub, executor, received, got = _pub_sub(ctx, executor_cls)
        spinner = SpinThread(executor, 'test').start()
        for i in range(200):  # publish until the subscription has matched and one message arrived
            pub.publish(Int32(data=i))
            if got.wait(0.05):
                break
        assert received, 'no message was delivered while spinning'
        assert spinner.stop(timeout=5.0)
        assert not spinner.running
        node.destroy_node()


def test_stop_after_the_context_is_shut_down_returns():
    with ros_context() as ctx:
        node, _, executor, _, _ = _pub_sub(ctx, SingleThreadedExecutor)
        spinner = SpinThread(executor).start()
        ctx.try_shutdown()
        assert spinner.stop(timeout=5.0)
        node.destroy_node()


class _ShutsDownWhileSpinning(SingleThreadedExecutor):
    """Its context is shut down inside spin_once, after SpinThread's check: the window a racing shutdown hits."""

    def spin_once(self, timeout_sec=None):
        self.context.try_shutdown()
        super().spin_once(timeout_sec=timeout_sec)


def test_a_shutdown_inside_spin_once_ends_the_thread_quietly():
    with ros_context() as ctx:
        node = Node('spin_thread_shutdown', context=ctx)
        executor = _ShutsDownWhileSpinning(context=ctx)
        executor.add_node(node)
        spinner = SpinThread(executor).start()
        wait_for(lambda: not spinner.running, what='the spin thread to end')
        assert spinner.stop(timeout=5.0)
        node.destroy_node()


def test_pace_rests_after_each_callback_and_stop_cuts_a_rest_short():
    with ros_context() as ctx:
        node = Node('spin_thread_pace', context=ctx)
        ticks = []
        node.create_timer(0.001, lambda: ticks.append(1))  # always ready: without a rest, ~1000 callbacks/s
        rests = []

        def pace() -> float:
            rests.append(len(ticks))
            return 0.05 if len(ticks) < 5 else 3600.0  # five short rests, then one that only stop() can end
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(node)
        spinner = SpinThread(executor, 'paced', pace=pace).start()
        wait_for(lambda: len(ticks) >= 5, what='five timer callbacks')
        time.sleep(0.3)  # the wall clock is the subject: 300 more callbacks would run here without the rest
        # One callback per rest: the thread rests after every callback, and never runs ahead of its pace.
        assert len(ticks) == 5 and len(rests) == 5
        assert spinner.stop(timeout=2.0)  # the hour-long rest ends at once
        node.destroy_node()


@pytest.mark.parametrize('executor_cls', [SingleThreadedExecutor, MultiThreadedExecutor])
def test_stop_ends_a_wait_that_nothing_else_would_end(executor_cls, monkeypatch):
    """rclpy's wake() lets a spin_once with nothing to run wait on until its timeout: stop() must end it itself
    (here the timeout is an hour, the join's deadline a minute)."""
    monkeypatch.setattr(spin_thread, 'WAKE_PERIOD', 3600.0)
    with ros_context() as ctx:
        node = Node('spin_thread_idle', context=ctx)
        executor = executor_cls(context=ctx)
        executor.add_node(node)
        ran = threading.Event()
        once = node.create_guard_condition(ran.set)
        spinner = SpinThread(executor).start()
        once.trigger()
        assert ran.wait(60.0)  # the thread has run a callback and waits again, with nothing left to run
        assert spinner.stop(timeout=60.0)
        assert not spinner.running
        node.destroy_node()
