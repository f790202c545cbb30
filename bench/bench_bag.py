"""The bag recorder's cost: CPU of its thread per recorded message, with rclpy's EventsExecutor (what
``execution/bag_recorder.py`` uses) and with the SingleThreadedExecutor it replaced.

Why it matters: ``make parts`` records 100 glue runs (about 15,000 messages each) in the workers' processes, beside
the client and three simulations on two cores, within its 10 minutes. ur_sim runs at real time here (every
per-cycle topic at 500 Hz), and the recorder records for ``SECONDS`` of wall time; the CPU is its spinning thread's
own (``pthread_getcpuclockid``), so it does not depend on what else the machine does.
"""
from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor

from bench.bench_sim import _SimProcess
from ur_glue_planner.execution import bag_recorder
from ur_glue_planner.execution.bag_recorder import BagRecorder

SECONDS = float(os.environ.get('UR_SIM_BENCH_BAG_SECONDS', '20'))  # [s] of wall time recorded per executor


def _record(executor_class, folder: Path, context: Context) -> dict:
    """Record for SECONDS with the recorder spinning `executor_class`; its thread's CPU and the messages."""
    saved = bag_recorder.EventsExecutor
    bag_recorder.EventsExecutor = executor_class  # the recorder's executor, for this measurement only
    try:
        recorder = BagRecorder(context, folder / executor_class.__name__, log=lambda _: None).start()
        thread = recorder._spinner._thread  # the recording thread, to read its CPU clock
        cpu0 = time.clock_gettime(time.pthread_getcpuclockid(thread.ident))
        time.sleep(SECONDS)  # the measurement's window: wall time is its subject
        cpu = time.clock_gettime(time.pthread_getcpuclockid(thread.ident)) - cpu0
        counts = recorder.close()
    finally:
        bag_recorder.EventsExecutor = saved
    messages = sum(counts.values())
    return {'executor': executor_class.__name__, 'seconds': SECONDS, 'messages': messages,
            'thread_cpu_s': round(cpu, 3), 'cpu_per_message_us': round(1e6 * cpu / max(messages, 1), 1)}


def run() -> dict:
    os.environ.setdefault('ROS_DOMAIN_ID', '180')
    sim = _SimProcess('-p', 'real_time_factor:=1.0')
    context = Context()
    rclpy.init(context=context)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            # the first recording also waits for ur_sim to come up (start() waits for a joint state)
            _record(EventsExecutor, Path(tmp) / 'warm_up', context)
            results = [_record(c, Path(tmp), context) for c in (EventsExecutor, SingleThreadedExecutor)]
    finally:
        rclpy.try_shutdown(context=context)
        sim.stop()
    return {'machine': {'cpus': os.cpu_count(), 'processor': platform.processor() or platform.machine(),
                        'python': platform.python_version(), 'load_average_1min': os.getloadavg()[0]},
            'recorder': results}
