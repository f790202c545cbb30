"""Large trajectories: a 100,000-point goal and topic message against ur_sim in real time.

Writes out/bench/intake.json (through `python -m bench`): time to accept the goal, the largest gap between
/joint_states messages meanwhile (recorded by a process of its own), ur_sim's memory (both of its processes)
before, during and after, and how soon speed_scaling_input takes effect while a long message is being read.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTrajectoryControllerState, SpeedScalingFactor
from rclpy.qos import QoSProfile
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bench.bench_sim import HOME, JOINTS, _Probe, _SimProcess, _wait
from ur_common.action_client import ActionClient
from ur_sim_driver.controllers.joint_trajectory import SPEED_SCALING_QOS

N = 100_000
CTRL = '/scaled_joint_trajectory_controller'


def _trajectory(n: int = N, dt: float = 0.001) -> JointTrajectory:
    """n points dt apart [s], a slow 0.1 rad sine on the first joint, with velocities."""
    t = dt * np.arange(1, n + 1)
    w = 2 * np.pi / (n * dt)
    points = []
    for k in range(n):
        q = HOME.copy()
        q[0] += 0.1 * np.sin(w * t[k])
        qd = np.zeros(6)
        qd[0] = 0.1 * w * np.cos(w * t[k]) if k < n - 1 else 0.0
        ns = round(t[k] * 1e9)
        p = JointTrajectoryPoint(positions=q.tolist(), velocities=qd.tolist())
        p.time_from_start.sec, p.time_from_start.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        points.append(p)
    return JointTrajectory(joint_names=JOINTS, points=points)


def _rss_mb(pid: int) -> dict:
    """Resident memory [MB] of ur_sim (`pid`) and of its controller interface process (its child)."""
    def rss(p: int) -> float:
        for line in Path(f'/proc/{p}/status').read_text().splitlines():
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
        return 0.0
    children = [int(c) for c in subprocess.run(['pgrep', '-P', str(pid)], capture_output=True,
                                               text=True).stdout.split()]
    return {'simulation': rss(pid), 'controller_interface': sum(rss(c) for c in children)}


def _gaps(path: Path, t0: float, t1: float) -> dict:
    rows = np.loadtxt(path, ndmin=2)
    wall = rows[(rows[:, 0] >= t0) & (rows[:, 0] <= t1), 0]
    periods = np.diff(wall)
    return {'messages': int(len(wall)), 'largest_gap_ms': float(periods.max() * 1e3),
            'p99_period_ms': float(np.percentile(periods, 99) * 1e3)}


def run() -> dict:
    sim = _SimProcess('-p', 'real_time_factor:=1.0')
    probe = _Probe()
    states: list[tuple[float, float]] = []  # (monotonic, speed_scaling_factor) of controller_state
    probe.node.create_subscription(JointTrajectoryControllerState, f'{CTRL}/controller_state',
                                   lambda m: states.append((time.monotonic(), m.speed_scaling_factor)),
                                   QoSProfile(depth=1000))
    client = ActionClient(probe.node, FollowJointTrajectory, f'{CTRL}/follow_joint_trajectory')
    topic = probe.node.create_publisher(JointTrajectory, f'{CTRL}/joint_trajectory', 10)
    scaling = probe.node.create_publisher(SpeedScalingFactor, f'{CTRL}/speed_scaling_input', SPEED_SCALING_QOS)
    tmp = Path(tempfile.mkdtemp(prefix='ur_sim_bench_'))
    recorder = None
    try:
        _wait(client.server_is_ready, 60.0, 'the action server')
        _wait(lambda: len(states) > 500, 30.0, 'controller_state')
        recorder = subprocess.Popen([sys.executable, '-m', 'bench.js_recorder', str(tmp / 'js.txt'), '60'])
        time.sleep(3.0)  # recorder discovery; ur_sim settles
        rss_before = _rss_mb(sim.proc.pid)
        # --- the goal ---
        goal = FollowJointTrajectory.Goal()
        goal.trajectory = _trajectory()
        t_send = time.monotonic()
        future = client.send_goal_async(goal)
        t_sent = time.monotonic()  # the client has converted, serialized and written the request
        _wait(future.done, 60.0, 'the goal response')
        t_accepted = time.monotonic()
        handle = future.result()
        del goal
        time.sleep(1.0)
        rss_during = _rss_mb(sim.proc.pid)
        cancel = handle.cancel_goal_async()
        _wait(cancel.done, 10.0, 'the cancel')
        result = handle.get_result_async()
        _wait(result.done, 10.0, 'the result')
        t_goal_done = time.monotonic()
        time.sleep(2.0)
        rss_after_goal = _rss_mb(sim.proc.pid)
        # --- the topic, with a speed scaling change while it is read ---
        msg = _trajectory()
        t_topic = time.monotonic()
        topic.publish(msg)
        t_scaling = time.monotonic()
        scaling.publish(SpeedScalingFactor(factor=0.5))
        _wait(lambda: any(t > t_scaling and abs(f - 0.5) < 1e-9 for t, f in states[-2000:]), 10.0, 'factor 0.5')
        t_applied = next(t for t, f in states if t > t_scaling and abs(f - 0.5) < 1e-9)
        del msg
        time.sleep(2.0)
        scaling.publish(SpeedScalingFactor(factor=1.0))
        topic.publish(JointTrajectory(joint_names=JOINTS, points=[
            JointTrajectoryPoint(positions=HOME.tolist(), velocities=[0.0] * 6, time_from_start=_sec(1.0))]))
        time.sleep(3.0)
        t_topic_done = time.monotonic()
        rss_after_topic = _rss_mb(sim.proc.pid)
        recorder.wait(timeout=90)
        recorder = None
        return {
            'points': N,
            'goal': {'accept_s': t_accepted - t_send, 'client_send_s': t_sent - t_send,
                     **_gaps(tmp / 'js.txt', t_send, t_goal_done),
                     'note': 'accept_s: send_goal_async to the goal response at the client, including the '
                             "client's own conversion and serialization (client_send_s: until send_goal_async "
                             "returns; rclpy in this process, slowed by this process's other threads), the "
                             "transfer, and ur_sim's controller process taking, reading and validating it"},
            'topic': {**_gaps(tmp / 'js.txt', t_topic, t_topic_done),
                      'speed_scaling_applied_ms': (t_applied - t_scaling) * 1e3,
                      'note': 'speed_scaling_applied_ms: publishing speed_scaling_input 0.5 right after the long '
                              'message to the first controller_state reporting it (both DDS hops included; '
                              'the control period is 2 ms)'},
            'rss_mb': {'before': rss_before, 'during_goal': rss_during, 'after_goal': rss_after_goal,
                       'after_topic': rss_after_topic,
                       'note': "VmRSS of ur_sim's two processes"},
        }
    finally:
        if recorder is not None:
            recorder.kill()
        probe.close()
        sim.stop()


def _sec(t: float) -> Duration:
    ns = round(t * 1e9)
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
