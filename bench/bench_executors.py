"""What two executor choices buy, in CPU: the glue client's spin thread on rclpy's EventsExecutor (what
``execution/client.py`` uses) against the SingleThreadedExecutor it replaced, and ur_sim's busy nodes on an executor
of their own (``ros/node.py`` ``make_executors``: ur_sim's node with the pace topic on an EventsExecutor) against one
executor for every node.

Why it matters: ``make parts`` runs 100 glue runs beside three simulations on two cores within its 10 minutes; per
run the client takes about 27,000 messages and ur_sim's executors wake about 2,000 times (the pace topic, the
trajectory_until_node's client of the trajectory action).

* client: ur_sim at real time (500 Hz), the client connected for ``SECONDS`` of wall time; the CPU is its spinning
  thread's own (``pthread_getcpuclockid``), so it does not depend on what else the machine does;
* ur_sim: an in-process ur_sim whose loop does not run, its executors spinning, and ``PACE_MESSAGES`` messages on
  its pace topic at ``PACE_RATE``; the CPU is the process's, less an idle window of the same length.
"""
from __future__ import annotations

import os
import platform
import time

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from bench.bench_sim import _SimProcess
from ur_glue_planner.execution import client as client_module
from ur_glue_planner.execution.client import URClient
from ur_sim_driver.ros.node import PACE_QOS, UrSimNode, make_executors
from ur_sim_driver.spin_thread import SpinThread

SECONDS = float(os.environ.get('UR_SIM_BENCH_EXECUTOR_SECONDS', '10'))  # [s] of wall time per client measurement
PACE_MESSAGES = 400
PACE_RATE = 40.0  # [Hz] about what a glue run sends per second of robot time
PORTS = ('dashboard_server', 'rtde', 'primary', 'secondary', 'realtime')


def _client_cpu(executor_class, context: Context) -> dict:
    saved = client_module.events_executor
    client_module.events_executor = lambda c: executor_class(context=c)  # the client's executor, for this only
    try:
        ur = URClient(context=context, timeout=60.0, node_name=f'bench_{executor_class.__name__.lower()}')
    finally:
        client_module.events_executor = saved
    try:
        thread = ur._spinner._thread
        recorder = ur.start_recording(50.0)  # a recording on: the client takes every joint state, as during a goal
        cpu0 = time.clock_gettime(time.pthread_getcpuclockid(thread.ident))
        time.sleep(SECONDS)  # the measurement's window: wall time is its subject
        cpu = time.clock_gettime(time.pthread_getcpuclockid(thread.ident)) - cpu0
        ur.stop_recording(recorder)
    finally:
        ur.close()
    return {'executor': executor_class.__name__, 'seconds': SECONDS, 'thread_cpu_s': round(cpu, 3),
            'cpu_per_robot_second_ms': round(1e3 * cpu / SECONDS, 1)}


def client_executors() -> list[dict]:
    sim = _SimProcess('-p', 'real_time_factor:=1.0')
    context = Context()
    rclpy.init(context=context)
    try:
        _client_cpu(EventsExecutor, context)  # also waits for ur_sim to come up
        return [_client_cpu(c, context) for c in (EventsExecutor, SingleThreadedExecutor)]
    finally:
        rclpy.try_shutdown(context=context)
        sim.stop()


def _ur_sim_cpu(split: bool) -> dict:
    context = Context()
    rclpy.init(context=context)
    params = [Parameter('pace_topic', value='/ur_sim/pace')]
    params += [Parameter(f'{port}.port', value=0) for port in PORTS]
    node = UrSimNode(context=context, parameter_overrides=params, start=False)
    spinners = [SpinThread(e, 'bench_executor').start() for e in make_executors(node, split)]
    sender = Node('bench_pace', context=context)
    pace = sender.create_publisher(Clock, '/ur_sim/pace', PACE_QOS)
    try:
        deadline = time.monotonic() + 30.0
        while pace.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)  # discovery: no ROS event to wait on from this thread
        window = PACE_MESSAGES / PACE_RATE
        idle0 = time.process_time()
        time.sleep(window)
        idle = time.process_time() - idle0
        cpu0 = time.process_time()
        for k in range(PACE_MESSAGES):
            msg = Clock()
            msg.clock.sec, msg.clock.nanosec = k, 0
            pace.publish(msg)
            time.sleep(1.0 / PACE_RATE)  # the sender's rate: wall time is the subject
        cpu = time.process_time() - cpu0 - idle
    finally:
        for spinner in spinners:
            spinner.stop()
        node.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return {'executors': len(spinners), 'split': split, 'messages': PACE_MESSAGES,
            'cpu_s': round(cpu, 3), 'cpu_per_message_us': round(1e6 * cpu / PACE_MESSAGES, 1)}


def run() -> dict:
    os.environ.setdefault('ROS_DOMAIN_ID', '181')
    return {'machine': {'cpus': os.cpu_count(), 'processor': platform.processor() or platform.machine(),
                        'python': platform.python_version(), 'load_average_1min': os.getloadavg()[0]},
            'client': client_executors(),
            'ur_sim_pace': [_ur_sim_cpu(split) for split in (True, False)]}
