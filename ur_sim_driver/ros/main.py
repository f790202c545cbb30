"""The ``ur_sim`` executable: the node (``node.py``) on its executors, until SIGINT or SIGTERM."""
from __future__ import annotations

import gc
import signal
import sys
import threading

import rclpy
from rclpy.executors import Executor, ExternalShutdownException, MultiThreadedExecutor
from rclpy.signals import SignalHandlerOptions

from ur_common.spin_thread import SpinThread, events_executor
from ur_sim_driver.errors import UrSimError
from ur_sim_driver.ros.node import UrSimNode

GIL_SWITCH_INTERVAL = 2e-4  # [s]
# Component nodes woken often enough to spin on an executor of their own (make_executors).
BUSY_NODES = ('trajectory_until_node',)


def make_executors(node: UrSimNode, split: bool = True) -> list[Executor]:
    """The executors spinning ur_sim's nodes. rclpy's MultiThreadedExecutor walks every entity of its nodes at each
    wake (about 2 ms for ur_sim's 200 services, subscriptions and event handlers), and two nodes wake it about 40
    times a second of a glue run each: with `split` they spin apart (``python -m bench executors``):

    * ur_sim's own node (`node`), whose only entities besides its parameter services are the pace topic's
      subscription (none of its callbacks waits), on rclpy's EventsExecutor, which handles an event without walking
      anything;
    * the trajectory_until_node (its client of the trajectory action gets every goal's feedback) on a
      MultiThreadedExecutor of its own: its goal callbacks wait for that client's answers;
    * the rest on a MultiThreadedExecutor: service callbacks wait for the simulation's cycles.
    """
    executors: list[Executor] = [MultiThreadedExecutor(num_threads=4, context=node.context)]
    if not split:
        for n in node.nodes():
            executors[0].add_node(n)
        return executors
    own, busy = events_executor(node.context), MultiThreadedExecutor(num_threads=4, context=node.context)
    executors += [own, busy]
    for n in node.nodes():
        (own if n is node else busy if n.get_name() in BUSY_NODES else executors[0]).add_node(n)
    return executors


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_sim` (and `ros2 run ur_sim_driver ur_sim`). Exits 0 on SIGINT/SIGTERM, 2 on bad parameters."""
    # The simulation thread gives up the GIL in every MuJoCo and rcl call; with the default 5 ms switch
    # interval each hand-back can stall it behind an executor thread, which caps the loop far below 500 Hz.
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    # Our own signal handling: stop the simulation thread first, then shut the context down, so that no
    # publish races the context's destruction.
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    node = None
    executors: list[Executor] = []
    spinners: list[SpinThread] = []
    code = 0
    try:
        node = UrSimNode()
        executors = make_executors(node)
        # Everything built so far (models, nodes, messages) lives until exit: out of the collector's sight, its
        # full collections take microseconds instead of milliseconds that the loop thread would wait out.
        gc.freeze()
        # The executors wait in threads of their own, woken by work or once a second; this thread waits for the
        # signal. (Waking every 0.1 s to look at `stop` rebuilt the wait set of some 150 entities each time: about
        # 3 ms of interpreter time, which the loop thread shared.)
        spinners = [SpinThread(e, f'ur_sim_executor_{i}').start() for i, e in enumerate(executors)]
        while not stop.wait(0.5) and rclpy.ok() and all(s.running for s in spinners):
            pass
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except UrSimError as exc:
        print(f'ur_sim: {exc}', file=sys.stderr)
        code = 2
    finally:
        if node is not None:
            node.shutdown()
        for spinner in spinners:
            spinner.stop(timeout=2.0)
        if not spinners:
            for executor in executors:
                executor.shutdown(timeout_sec=2.0)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == '__main__':
    sys.exit(main())
