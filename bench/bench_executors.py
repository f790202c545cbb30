"""What ur_sim's executors buy, in CPU: its busy nodes on executors of their own (``ros/main.py`` ``make_executors``:
ur_sim's own node, with the pace topic, on rclpy's EventsExecutor; the trajectory_until_node on a
MultiThreadedExecutor of its own) against one executor for every node.

Why it matters: ``make parts`` runs 100 glue runs beside three simulations on two cores; per part ur_sim's executors
woke about 2,200 times (1,014 pace messages, 1,148 feedback and status messages of the trajectory_until_node's
action client). An in-process ur_sim whose loop does not run, its executors spinning, gets ``PACE_MESSAGES``
messages on its pace topic at ``PACE_RATE``; the CPU is the process's, less an idle window of the same length.
"""
from __future__ import annotations

import os
import platform
import time

import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from ur_common.spin_thread import SpinThread
from ur_sim_driver.ros.main import make_executors
from ur_sim_driver.ros.node import UrSimNode
from ur_sim_driver.ros.pace_gate import PACE_QOS

PACE_MESSAGES = 400
PACE_RATE = 40.0  # [Hz] about what a glue run sends per second of robot time
PORTS = ('dashboard_server', 'rtde', 'primary', 'secondary', 'realtime')


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
            'ur_sim_pace': [_ur_sim_cpu(split) for split in (True, False)]}
