"""What each mechanism that exists only for speed buys, against the simplest alternative (issue 21).

Writes out/bench/tricks.json (through `python -m bench`). Every row is measured both ways on this machine:

* goal intake: ``goal_intake.py`` (goal requests read into arrays through rclpy's conversion hook) against
  rclpy's own conversion of the request followed by ``from_points``, for a 100,000-point goal;
* topic intake: ``trajectory_cdr.py`` (strided numpy views) and ``cdr.py`` (a point-by-point CDR reader) against
  rclpy's deserialization followed by ``from_points``, for a 100,000-point message;
* the second process: the longest period of a 2 ms loop thread (the simulation's) while a 100,000-point goal is
  taken in by another process, by the same process with the array intake, and with rclpy's conversion;
* per-cycle publishing: ``CdrTemplate`` patching serialized bytes against building the message and publishing it
  (``/joint_states`` and ``controller_state``, the largest per-cycle messages), and the publisher handle's
  ``publish_raw`` against rclpy's ``publish(bytes)``;
* SCHED_FIFO on the simulation loop: ``/joint_states`` periods in real time with ``thread_priority`` 50 (the
  default) and 0, `REALTIME_S` each, twice in turn.
"""
from __future__ import annotations

import ctypes
import gc
import subprocess
import sys
import threading
import time

import numpy as np
import rclpy
from control_msgs.msg import JointTrajectoryControllerState
from rclpy.context import Context
from rclpy.node import Node
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bench.bench_sim import realtime_periods
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.controllers.controller_state import FIELDS as STATE_FIELDS
from ur_sim_driver.gateway import goal_intake as gi
from ur_sim_driver.gateway.cdr import parse_joint_trajectory
from ur_sim_driver.gateway.trajectory_cdr import read_joint_trajectory
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion.command_arrays import from_points

N = 100_000
PERIOD = 0.002  # [s] the simulation loop's control period at 500 Hz
PUBLISHES = 3000
REALTIME_S = 60.0  # [s] of /joint_states per run


def _points(n: int) -> list[JointTrajectoryPoint]:
    points = []
    for k in range(n):
        p = JointTrajectoryPoint(positions=[0.001 * k + i for i in range(6)], velocities=[0.01 * i for i in range(6)])
        ns = (k + 1) * 1_000_000
        p.time_from_start.sec, p.time_from_start.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        points.append(p)
    return points


class _Loop:
    """A thread that wakes every PERIOD, as the simulation loop does, and records its periods [s]."""

    def __init__(self) -> None:
        self.stamps: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        due = time.perf_counter()
        while not self._stop.is_set():
            self.stamps.append(time.perf_counter())
            due += PERIOD
            rest = due - time.perf_counter()
            if rest > 0:
                time.sleep(rest)

    def __enter__(self) -> _Loop:
        self._thread.start()
        time.sleep(0.2)
        return self

    def __exit__(self, *exc) -> None:
        time.sleep(0.2)
        self._stop.set()
        self._thread.join()

    def longest_ms(self) -> float:
        return float(np.diff(self.stamps).max() * 1e3)


class _CRequest:
    """A SendGoal request with `n` points converted to C, as rclpy hands a taken request to its conversion."""

    def __init__(self, intake: gi.GoalIntake, n: int) -> None:
        request = gi.Request()
        traj = request.goal.trajectory
        traj.joint_names = [f'joint_{i}' for i in range(6)]
        traj.points = _points(n)
        meta = type(gi.Request)
        self._create = ctypes.CFUNCTYPE(ctypes.c_void_p)(gi._pointer(meta._CREATE_ROS_MESSAGE))
        self._destroy = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(gi._pointer(meta._DESTROY_ROS_MESSAGE))
        from_py = ctypes.PYFUNCTYPE(ctypes.c_bool, ctypes.py_object, ctypes.c_void_p)(
            gi._pointer(meta._CONVERT_FROM_PY))
        self.address = self._create()
        if not from_py(request, self.address):
            raise RuntimeError('the request did not convert to C')

    def close(self) -> None:
        self._destroy(self.address)


def _rclpy_goal(intake: gi.GoalIntake, address: int):
    """What the gateway does without the intake: rclpy's conversion, then the arrays from the points."""
    request = intake._standard(address)
    traj = request.goal.trajectory
    return from_points(traj.joint_names, conv.time_to_sec(traj.header.stamp), traj.points)


def _timed(fn, repeat: int = 3) -> tuple[float, float]:
    """(best time [s], the loop thread's longest period [ms] over all repeats) of fn() in this process."""
    best = float('inf')
    with _Loop() as loop:
        for _ in range(repeat):
            gc.collect()
            t0 = time.perf_counter()
            fn()
            best = min(best, time.perf_counter() - t0)
    return best, loop.longest_ms()


def goal_intake_figures(n: int = N) -> dict:
    intake = gi.goal_intake()
    if intake is None:
        return {'error': gi.intake_error()}
    request = _CRequest(intake, n)
    try:
        arrays_s, arrays_stall = _timed(lambda: intake.split(request.address))
        rclpy_s, rclpy_stall = _timed(lambda: _rclpy_goal(intake, request.address), repeat=2)
    finally:
        request.close()
    # The same intake in a process of its own (the gateway), while this process's loop runs.
    code = ('from bench.bench_tricks import _CRequest, N; from ur_sim_driver.gateway import goal_intake as gi; '
            'import time, sys; i = gi.goal_intake(); r = _CRequest(i, N); print("ready", flush=True); '
            'sys.stdin.readline(); t = time.perf_counter(); i.split(r.address); '
            'print(time.perf_counter() - t, flush=True); r.close()')
    child = subprocess.Popen([sys.executable, '-c', code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == 'ready'
        with _Loop() as loop:
            child.stdin.write('go\n')
            child.stdin.flush()
            other_s = float(child.stdout.readline())
        other_stall = loop.longest_ms()
    finally:
        child.wait(timeout=60)
    return {'points': n,
            'arrays_intake_s': arrays_s, 'rclpy_conversion_s': rclpy_s,
            'loop_longest_period_ms': {'intake_in_another_process': other_stall,
                                       'array_intake_in_this_process': arrays_stall,
                                       'rclpy_conversion_in_this_process': rclpy_stall},
            'intake_in_another_process_s': other_s}


def topic_intake_figures(n: int = N) -> dict:
    data = serialize_message(JointTrajectory(joint_names=[f'joint_{i}' for i in range(6)], points=_points(n)))

    def rclpy_way():
        msg = deserialize_message(data, JointTrajectory)
        return from_points(msg.joint_names, conv.time_to_sec(msg.header.stamp), msg.points)
    strided_s, _ = _timed(lambda: read_joint_trajectory(data))
    general_s, _ = _timed(lambda: parse_joint_trajectory(data))
    rclpy_s, _ = _timed(rclpy_way, repeat=2)
    return {'points': n, 'bytes': len(data), 'strided_views_s': strided_s, 'point_by_point_cdr_s': general_s,
            'rclpy_deserialize_s': rclpy_s}


def publish_figures(count: int = PUBLISHES) -> dict:
    ctx = Context()
    rclpy.init(context=ctx)
    node = Node('bench_publish', context=ctx)
    names = [f'joint_{i}' for i in range(6)]
    out = {}
    try:
        js_pub = node.create_publisher(JointState, 'bench_js', 10)
        state_pub = node.create_publisher(JointTrajectoryControllerState, 'bench_state', 10)
        js_template = CdrTemplate(JointState(name=names, position=[0.0] * 6, velocity=[0.0] * 6, effort=[0.0] * 6),
                                  stamps=('header.stamp',), floats=('position', 'velocity', 'effort'),
                                  publisher=js_pub)
        proto = JointTrajectoryControllerState(joint_names=names)
        paths = []
        for point, fields in STATE_FIELDS:
            for field in fields:
                setattr(getattr(proto, point), field, [0.0] * 6)
                paths.append(f'{point}.{field}')
        state_template = CdrTemplate(proto, stamps=('header.stamp',), floats=(*paths, 'speed_scaling_factor'),
                                     publisher=state_pub)
        q = np.linspace(0.1, 0.6, 6)
        js_values = np.concatenate([q, q, q])
        state_values = np.concatenate([q] * len(paths) + [np.ones(1)])

        def per_publish_us(fn) -> float:
            best = float('inf')
            for _ in range(3):
                t0 = time.perf_counter()
                for k in range(count):
                    fn(k)
                best = min(best, (time.perf_counter() - t0) / count * 1e6)
            return best

        def js_message(k: int) -> None:
            msg = JointState(name=names, position=q.tolist(), velocity=q.tolist(), effort=q.tolist())
            msg.header.stamp.sec, msg.header.stamp.nanosec = k, 0
            js_pub.publish(msg)

        def state_message(k: int) -> None:
            msg = JointTrajectoryControllerState(joint_names=names)
            msg.header.stamp.sec = k
            for point, fields in STATE_FIELDS:
                for field in fields:
                    setattr(getattr(msg, point), field, q.tolist())
            msg.speed_scaling_factor = 1.0
            state_pub.publish(msg)

        raw = js_pub.handle.publish_raw
        data = js_template.render(js_values, (1, 0))
        out = {
            'joint_states_us': {'cdr_template': per_publish_us(lambda k: js_template.publish(js_values, (k, 0))),
                                'message': per_publish_us(js_message)},
            'controller_state_us': {'cdr_template': per_publish_us(
                lambda k: state_template.publish(state_values, (k, 0))), 'message': per_publish_us(state_message)},
            'bytes_us': {'handle_publish_raw': per_publish_us(lambda k: raw(data)),
                         'publisher_publish_bytes': per_publish_us(lambda k: js_pub.publish(data))},
        }
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    return out


def sched_fifo_figures(seconds: float = REALTIME_S, pairs: int = 2) -> dict:
    """/joint_states periods with the loop under SCHED_FIFO 50 (the default) and at normal priority, in turn."""
    runs = {'thread_priority_50': [], 'thread_priority_0': []}
    for _ in range(pairs):
        runs['thread_priority_50'].append(realtime_periods(seconds))
        runs['thread_priority_0'].append(realtime_periods(seconds, 40, '-p', 'thread_priority:=0'))
    return runs


def rotvec_figures(count: int = 20000) -> dict:
    """A TCP orientation as a rotation vector, as RTDE and the real-time interface stream it every cycle
    (``rtde_fields._rotvec``): MuJoCo's C routines against SciPy's Rotation [us a conversion], and their largest
    difference over random rotations."""
    from scipy.spatial.transform import Rotation

    from ur_sim_driver.ports.rtde_fields import _rotvec

    rotations = Rotation.random(count, random_state=1)
    quats = [np.roll(q, 1) for q in rotations.as_quat()]  # (w, x, y, z)
    t0 = time.perf_counter()
    ours = [_rotvec(q) for q in quats]
    t1 = time.perf_counter()
    scipy = [Rotation.from_quat(np.roll(q, -1)).as_rotvec() for q in quats]
    t2 = time.perf_counter()
    return {'mujoco_us': 1e6 * (t1 - t0) / count, 'scipy_us': 1e6 * (t2 - t1) / count,
            'max_difference_rad': float(np.abs(np.array(ours) - np.array(scipy)).max())}


def run() -> dict:
    return {'goal_intake': goal_intake_figures(), 'topic_intake': topic_intake_figures(),
            'publish': publish_figures(), 'sched_fifo': sched_fifo_figures(), 'rotvec': rotvec_figures()}
