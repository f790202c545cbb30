"""The gateway process: one node serving every trajectory controller's interfaces (see ``gateway_link.py`` for why).

The node is ``ur_sim_trajectory_gateway`` (the controllers' own nodes, named after them as in ros2_control, are
ur_sim's); each controller's action server and topic are a ``TrajectoryGateway`` on it (``trajectory_gateway.py``).
A receiving thread hands the simulation's messages to the controller that owns them and its answers to the
questions waiting at the pipe (``sim_pipe.py``). The simulation starts this process, ends it through the pipe,
and owns Ctrl-C.
"""
from __future__ import annotations

import faulthandler
import signal
import sys
import threading
import time
from multiprocessing.connection import Connection

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from ur_sim_driver.gateway.dds_profile import free_received_samples
from ur_sim_driver.gateway.gateway_link import STOP, Admission, GatewayConfig
from ur_sim_driver.gateway.goal_intake import intake_error
from ur_sim_driver.gateway.memory import use_mmap_for_large_blocks
from ur_sim_driver.gateway.sim_pipe import SimPipe
from ur_sim_driver.gateway.trajectory_gateway import TrajectoryGateway

NODE_NAME = 'ur_sim_trajectory_gateway'
FINISH_TIMEOUT = 2.0  # [s] of wall time for the goals' execute callbacks to end at stop
RESULT_SPIN = 0.2  # [s] of wall time spun after them, for their results to go out


def _receive(pipe: SimPipe, gateways: dict[str, TrajectoryGateway], stopped: threading.Event,
             ended_goals: threading.Event) -> None:
    """Hand the simulation's messages to the controllers until it says stop or the pipe closes; then end their
    goals (`ended_goals` set if there were any) and set `stopped`."""
    try:
        while True:
            message = pipe.conn.recv()
            if message == STOP:
                break
            if isinstance(message, Admission):
                pipe.answered(message)
            else:
                for gateway in gateways.values():
                    if gateway.owns(message.token):
                        gateway.dispatch(message)
                        break
    except (OSError, EOFError):
        pass
    pipe.end_all()
    if sum(gateway.end_all() for gateway in gateways.values()) > 0:
        ended_goals.set()
    stopped.set()


def run_gateway(conn: Connection) -> None:
    """Serve the controllers' interfaces until the simulation says stop (or its end of the pipe closes)."""
    # The parent stops this process through the pipe; Ctrl-C in a terminal reaches both, and the parent must
    # be the one to decide (it ends the goals first).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    faulthandler.register(signal.SIGUSR1)  # `kill -USR1 <pid>` prints every thread's stack, for a hang
    use_mmap_for_large_blocks()
    cfg: GatewayConfig = conn.recv()
    profile = free_received_samples()  # a large goal's receive buffer is not kept after it
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    pipe = SimPipe(conn)
    executor = MultiThreadedExecutor(num_threads=4)
    try:
        node = Node(NODE_NAME, namespace=cfg.namespace or '/')
    finally:
        if profile is not None:
            profile.unlink(missing_ok=True)  # read when the node was made
    gateways = {name: TrajectoryGateway(node, cfg, name, pipe) for name in cfg.controllers}
    executor.add_node(node)
    if intake_error() is not None:
        node.get_logger().warning(
            f'goal requests are converted point by point (slow for long trajectories): {intake_error()}')
    stopped, ended_goals = threading.Event(), threading.Event()
    threading.Thread(target=_receive, args=(pipe, gateways, stopped, ended_goals), name='gateway_receive',
                     daemon=True).start()
    try:
        while not stopped.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
        # Let the execute callbacks return their (shutdown) results before the context goes: spun while a goal
        # executes, then RESULT_SPIN more for the results' sending (rclpy sends a result from a task of its own,
        # which the executor runs at a later spin). With no goal at the stop there is nothing to send: the fixed
        # spin had been most of every ur_sim's stop.
        if ended_goals.is_set() or any(gateway.busy() for gateway in gateways.values()):
            deadline = time.monotonic() + FINISH_TIMEOUT
            while any(gateway.busy() for gateway in gateways.values()) and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.01)
            until = time.monotonic() + RESULT_SPIN
            while time.monotonic() < until:
                executor.spin_once(timeout_sec=0.01)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown(timeout_sec=2.0)
        node.destroy_node()
        rclpy.try_shutdown()
        conn.close()


def main() -> None:
    """``python -m ur_sim_driver.gateway.gateway_process PIPE_FD``, as GatewayLink starts it."""
    run_gateway(Connection(int(sys.argv[1])))


if __name__ == '__main__':
    main()
