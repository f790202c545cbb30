"""`python -m bench.js_recorder OUT SECONDS [PRIORITY]`: record arrival times of /joint_states in a process of its own.

The benchmark that sends a 100,000-point trajectory spends seconds building and serializing it while holding
its GIL; a recorder in that process would see gaps that are its own. This one writes one line per message,
``monotonic_arrival stamp`` (time.monotonic is one clock for every process on the machine). With PRIORITY, it
receives under SCHED_FIFO at that priority where permitted, as a real-time client would: the gaps it records are
then the publisher's, not its own waits for a core on a loaded machine.
"""
from __future__ import annotations

import gc
import os
import sys
import time

import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState


def main() -> int:
    out, seconds = sys.argv[1], float(sys.argv[2])
    gc.disable()  # a collection pass over the growing list of rows would show as a gap of its own
    if len(sys.argv) > 3:
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(sys.argv[3])))
        except OSError as exc:
            print(f'js_recorder: normal scheduling ({exc.strerror})', file=sys.stderr)
    rclpy.init()
    node = Node('bench_js_recorder')
    rows: list[tuple[float, float]] = []
    node.create_subscription(
        JointState, '/joint_states',
        lambda m: rows.append((time.monotonic(), m.header.stamp.sec + m.header.stamp.nanosec * 1e-9)),
        QoSProfile(depth=1000))
    end = time.monotonic() + seconds
    try:
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
    finally:
        with open(out, 'w') as f:
            f.writelines(f'{w:.6f} {s:.6f}\n' for w, s in rows)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
