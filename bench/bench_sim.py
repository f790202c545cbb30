"""Simulator benchmark: real-time factor, /joint_states timing, goal latency and tracking error.

Writes out/bench/sim.json (through `python -m bench`). The simulator runs as its own process (`ur_sim`),
as users run it; the measuring side is this process.
"""
from __future__ import annotations

import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np
import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTrajectoryControllerState
from geometry_msgs.msg import PoseStamped, WrenchStamped
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rclpy.wait_for_message import wait_for_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage
from trajectory_msgs.msg import JointTrajectoryPoint
from ur_msgs.msg import IOStates, ToolDataMsg

from ur_common.action_client import ActionClient
from ur_common.spin_thread import SpinThread
from ur_sim_driver.motion.jtc import TrajectoryController
from ur_sim_driver.motion.tolerances import default_tolerances
from ur_sim_driver.motion.trajectory_types import TrajectoryCommand
from ur_sim_driver.motion.validation import map_to_config_order
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

RATE_WINDOW = float(os.environ.get('UR_SIM_BENCH_RATE_SECONDS', '5'))  # [s] of real-time /joint_states
JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint', 'wrist_2_joint',
          'wrist_3_joint']
HOME = np.array([0.0, -1.57, 0.0, -1.57, 0.0, 0.0])
# The standard 6-joint trajectory: every joint moves, through a via point with velocity, and back to rest.
STANDARD = dict(times=[1.5, 3.0, 4.5],
                positions=[HOME + [0.6, 0.4, -0.5, 0.5, 0.8, 1.0], HOME + [-0.3, 0.2, 0.4, -0.4, -0.5, 0.5],
                           HOME],
                velocities=[np.zeros(6), [-0.4, 0.0, 0.3, -0.3, -0.5, -0.2], np.zeros(6)],
                accelerations=[np.zeros(6)] * 3)


class _SimProcess:
    """`ur_sim` in its own process group, stopped with SIGINT."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(['ur_sim', '--ros-args', *args], stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL, start_new_session=True)

    def stop(self) -> int:
        os.killpg(self.proc.pid, signal.SIGINT)
        return self.proc.wait(timeout=20)


class _Probe:
    """A node on a private context, spun in a background thread."""

    def __init__(self) -> None:
        self.ctx = Context()
        rclpy.init(context=self.ctx)
        self.node = Node('bench_probe', context=self.ctx)
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self.spinner = SpinThread(self.executor, 'bench_probe').start()

    def close(self) -> None:
        self.spinner.stop()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.ctx)


def _wait(cond, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise TimeoutError(f'bench: timed out waiting for {what}')
        time.sleep(0.001)


def raw_mj_step_rtf(cfg_params: dict, seconds: float = 5.0) -> float:
    """RTF of bare mj_step on the simulator's own model (same timestep)."""
    sim = Simulator(sim_config_from_params(cfg_params))
    m, d = sim.physics.model, sim.physics.data
    steps = int(seconds / m.opt.timestep)
    t0 = time.perf_counter()
    for _ in range(steps):
        mujoco.mj_step(m, d)
    return seconds / (time.perf_counter() - t0)


def _clock_sample(node: Node) -> tuple[float, float]:
    """(wall [s], simulated [s]) of the next /clock message, from a subscription that exists only meanwhile: a
    subscriber held for the whole measurement would itself load the machine with thousands of messages a second."""
    ok, msg = wait_for_message(Clock, node, '/clock', time_to_wait=30.0)
    wall = time.perf_counter()
    if not ok:
        raise TimeoutError('bench: no /clock from ur_sim within 30 s')
    return wall, msg.clock.sec + msg.clock.nanosec * 1e-9


# Every topic ur_sim publishes each control cycle (robot_state_publisher's /tf: 20 Hz), with its type.
PER_CYCLE_TOPICS = (
    ('/joint_states', JointState), ('/tf', TFMessage), ('/tcp_pose_broadcaster/pose', PoseStamped),
    ('/scaled_joint_trajectory_controller/controller_state', JointTrajectoryControllerState),
    ('/speed_scaling_state_broadcaster/speed_scaling', Float64),
    ('/io_and_status_controller/io_states', IOStates), ('/io_and_status_controller/tool_data', ToolDataMsg),
    ('/force_torque_sensor_broadcaster/wrench', WrenchStamped), ('/clock', Clock))


def fast_mode_rtf(rounds: int = 5, window: float = 4.0, raw_seconds: float = 2.0, *args: str,
                  listen_all: bool = False) -> dict:
    """RTF of the ur_sim process in as-fast-as-possible mode, measured from outside, and of bare mj_step on the same
    model, interleaved: this machine's speed drifts by a factor of up to 2 from minute to minute, so each round
    pauses ur_sim (SIGSTOP) for `raw_seconds` of bare mj_step, resumes it (SIGCONT) and takes two /clock samples
    `window` [s] of wall time apart. The ratio is taken per round; its median is the figure. `args` are more
    parameters for ur_sim. ur_sim sends only the topics someone subscribes to (``cdr_template.listened``);
    `listen_all`: a subscription on every per-cycle topic all along (raw, never taken: the sending is measured,
    not this process's reading)."""
    sim = _SimProcess('-p', 'real_time_factor:=0.0', *args)
    ctx = Context()
    rclpy.init(context=ctx)
    node = Node('bench_clock_probe', context=ctx)
    if listen_all:
        for topic, msg_type in PER_CYCLE_TOPICS:
            node.create_subscription(msg_type, topic, lambda _: None, QoSProfile(depth=1), raw=True)
    cfg = {'ur_type': 'ur5e'}
    rows = []
    try:
        _clock_sample(node)  # ur_sim is up
        for _ in range(rounds):
            os.killpg(sim.proc.pid, signal.SIGSTOP)
            try:
                raw = raw_mj_step_rtf(cfg, raw_seconds)
            finally:
                os.killpg(sim.proc.pid, signal.SIGCONT)
            w0, s0 = _clock_sample(node)
            time.sleep(window)
            w1, s1 = _clock_sample(node)
            rtf = (s1 - s0) / (w1 - w0)
            rows.append({'rtf': rtf, 'raw_mj_step_rtf': raw, 'ratio': rtf / raw, 'wall_s': w1 - w0, 'sim_s': s1 - s0})
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
        sim.stop()
    sim_s, wall_s = sum(r['sim_s'] for r in rows), sum(r['wall_s'] for r in rows)
    return {'rtf': sim_s / wall_s, 'sim_s': sim_s, 'wall_s': wall_s,
            'raw_mj_step_rtf_median': float(np.median([r['raw_mj_step_rtf'] for r in rows])),
            'ratio_to_raw_median': float(np.median([r['ratio'] for r in rows])), 'rounds': rows}


def realtime_periods(seconds: float = 60.0, recorder_priority: int = 40, *args: str) -> dict:
    """/joint_states in real-time mode as a client sees it over `seconds`: every message's arrival time, recorded
    by a process of its own (bench/js_recorder.py, under SCHED_FIFO `recorder_priority` where permitted, below
    ur_sim's loop at its default 50), whose periods give the mean rate, p99 and max. `args`: more parameters for
    ur_sim."""
    sim = _SimProcess('-p', 'real_time_factor:=1.0', *args)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / 'js.txt'
        warm_up = 5.0  # [s] discovery and start-up, not counted
        recorder = subprocess.Popen([sys.executable, '-m', 'bench.js_recorder', str(out), str(seconds + warm_up),
                                     str(recorder_priority)])
        try:
            recorder.wait(timeout=seconds + warm_up + 60.0)
        finally:
            sim.stop()
        rows = np.loadtxt(out, ndmin=2)
    return {**period_stats(rows[:, 0], seconds), 'recorder_priority': recorder_priority,
            'targets': {'mean_within': '0.5 % of 500 Hz', 'p99_period_ms': 2.5, 'max_period_ms': 5.0}}


def period_stats(wall: np.ndarray, seconds: float) -> dict:
    """The periods between the arrivals `wall` [s] of the last `seconds`: mean rate, p50, p99, max, gaps."""
    wall = wall[wall >= wall[-1] - seconds]
    periods = np.diff(wall)
    return {'window_s': float(wall[-1] - wall[0]), 'messages': int(len(wall)),
            'mean_rate_hz': float((len(wall) - 1) / (wall[-1] - wall[0])),
            'period_ms': {'mean': float(periods.mean() * 1e3), 'p50': float(np.percentile(periods, 50) * 1e3),
                          'p99': float(np.percentile(periods, 99) * 1e3), 'max': float(periods.max() * 1e3)},
            'gaps_over_5ms': int((periods > 0.005).sum())}


def realtime_rate_and_latency() -> dict:
    """/joint_states periods in real-time mode, and the latency from goal acceptance to first motion."""
    sim = _SimProcess('-p', 'real_time_factor:=1.0')
    probe = _Probe()
    received: list[tuple[float, float, np.ndarray]] = []
    probe.node.create_subscription(
        JointState, '/joint_states',
        lambda m: received.append((time.perf_counter(), m.header.stamp.sec + m.header.stamp.nanosec * 1e-9,
                                   np.array(m.position))), QoSProfile(depth=100))
    client = ActionClient(probe.node, FollowJointTrajectory,
                          '/scaled_joint_trajectory_controller/follow_joint_trajectory')
    try:
        _wait(lambda: len(received) > 100, 30.0, '/joint_states')
        start = len(received)
        time.sleep(RATE_WINDOW)
        window = received[start:]
        wall = np.array([w for w, _, _ in window])
        periods = np.diff(wall)
        _wait(client.server_is_ready, 30.0, 'the action server')
        latencies = []
        for k in range(5):
            q0 = received[-1][2]
            goal = FollowJointTrajectory.Goal()
            goal.trajectory.joint_names = JOINTS
            target = q0 + (0.2 if k % 2 == 0 else -0.2)
            goal.trajectory.points = [JointTrajectoryPoint(positions=target.tolist(), velocities=[0.0] * 6,
                                                           time_from_start=Duration(sec=1))]
            n_before = len(received)
            sent_wall, sent_stamp = time.perf_counter(), received[-1][1]
            future = client.send_goal_async(goal)
            _wait(future.done, 10.0, 'goal response')
            accepted_wall = time.perf_counter()
            def moved(q0=q0, n_before=n_before):
                return next(((w, s) for w, s, p in received[n_before:] if np.abs(p - q0).max() > 1e-6), None)
            _wait(moved, 10.0, 'motion')
            first = moved()
            latencies.append({'wall_ms': (first[0] - sent_wall) * 1e3,
                              'response_ms': (accepted_wall - sent_wall) * 1e3,
                              'sim_ms': (first[1] - sent_stamp) * 1e3})
            result = future.result().get_result_async()
            _wait(result.done, 10.0, 'result')
        return {
            'window_s': RATE_WINDOW,
            'messages': len(window),
            'mean_rate_hz': (len(window) - 1) / (wall[-1] - wall[0]),
            'period_ms': {'p50': float(np.percentile(periods, 50) * 1e3),
                          'p99': float(np.percentile(periods, 99) * 1e3), 'max': float(periods.max() * 1e3)},
            'goal_to_first_motion_ms': {
                'wall_max': max(x['wall_ms'] for x in latencies),
                'wall_mean': float(np.mean([x['wall_ms'] for x in latencies])),
                'goal_response_mean': float(np.mean([x['response_ms'] for x in latencies])),
                'sim_max': max(x['sim_ms'] for x in latencies),
                'note': 'wall: from send_goal_async at the client to the first moved /joint_states received by the '
                        'client (both DDS hops included); sim: stamp of that message minus the newest stamp the '
                        'client had when it sent the goal',
            },
        }
    finally:
        probe.close()
        sim.stop()


def tracking_error(ur_type: str = 'ur5e') -> dict:
    """Max |reference - measured| over the standard 6-joint trajectory, in the core loop the node runs."""
    cfg = sim_config_from_params({'ur_type': ur_type})
    sim = Simulator(cfg)
    tol = default_tolerances(cfg.joints, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=0.0)
    state = sim.state()
    jtc = TrajectoryController(cfg.joints, tol, state.q, sim.params.v_max, sim.a_max)
    cmd = TrajectoryCommand.from_arrays(JOINTS, **STANDARD)
    jtc.start(map_to_config_order(cmd, cfg.joints, state.q), state.t, state.q, state.qd, token='bench')
    worst = np.zeros(6)
    steps = int(5.0 / sim.control_dt)
    for _ in range(steps):
        state = sim.state()
        ref, _ = jtc.update(state.t, sim.control_dt, state.q, state.qd)
        worst = np.maximum(worst, np.abs(ref.positions - state.q))
        sim.advance(state, ref, jtc.stop)
    return {'ur_type': ur_type, 'control_rate_hz': sim.control_rate, 'max_error_mrad': float(worst.max() * 1e3),
            'per_joint_mrad': (worst * 1e3).round(4).tolist()}


def cycle_profile(cycles: int = 5000, listen_all: bool = True) -> dict:
    """Where one control cycle's time goes, in-process (ur5e, 500 Hz, holding), without an executor: the mean
    wall time [us] of each active component's update (its topics: building and publishing) and of the rest of
    the cycle (the locked part: robot state, controller, servo, computed torque, physics step, safety).
    `listen_all`: every per-cycle topic has a subscriber (another node of this process, never taking its
    messages), so every topic is built and sent; without, none is."""
    from ur_sim_driver.ros.node import UrSimNode  # here: the benchmark's other parts need no in-process node

    ctx = Context()
    rclpy.init(context=ctx, domain_id=int(os.environ.get('UR_SIM_BENCH_PROFILE_DOMAIN', '179')))
    node = UrSimNode(context=ctx, start=False)
    listener = Node('bench_listener', context=ctx)
    if listen_all:
        subs = [listener.create_subscription(msg_type, topic, lambda _: None, QoSProfile(depth=1), raw=True)
                for topic, msg_type in PER_CYCLE_TOPICS]
        _wait(lambda: all(s.get_publisher_count() > 0 for s in subs), 30.0, 'matched per-cycle topics')
    spent: dict[str, float] = {}

    def timed(name: str, update):
        def wrapper(cycle) -> None:
            t0 = time.perf_counter()
            update(cycle)
            spent[name] = spent.get(name, 0.0) + time.perf_counter() - t0
        return wrapper

    for c in node.components:
        c.update = timed(c.name, c.update)
    publish = node._publish
    node._publish = timed('/clock', publish)
    try:
        for _ in range(500):
            node.step_once()
        spent.clear()
        t0 = time.perf_counter()
        for _ in range(cycles):
            node.step_once()
        total = (time.perf_counter() - t0) / cycles
    finally:
        node.shutdown()
        node.destroy_node()
        listener.destroy_node()
        rclpy.try_shutdown(context=ctx)
    per = {name: 1e6 * s / cycles for name, s in sorted(spent.items(), key=lambda kv: -kv[1]) if s > 0}
    return {'cycle_us': 1e6 * total, 'control_and_physics_us': 1e6 * total - sum(per.values()),
            'components_us': per, 'cycles': cycles, 'every_topic_listened': listen_all}


def run() -> dict:
    fast = fast_mode_rtf()
    listened = fast_mode_rtf(listen_all=True)
    periods = realtime_periods(60.0)
    latency = realtime_rate_and_latency()
    return {
        'machine': {'cpus': os.cpu_count(), 'processor': platform.processor() or platform.machine(),
                    'python': platform.python_version(), 'mujoco': mujoco.__version__,
                    'load_average_1min': os.getloadavg()[0]},
        'fast_mode': {'ur_type': 'ur5e', 'control_rate_hz': 500, **fast,
                      'targets': {'rtf': 30.0, 'ratio_to_raw': 0.10}},
        # The same with a subscriber on every per-cycle topic: each one built and sent.
        'fast_mode_every_topic_listened': {'ur_type': 'ur5e', 'control_rate_hz': 500, **listened},
        'cycle_profile': cycle_profile(),
        'cycle_profile_nothing_listened': cycle_profile(listen_all=False),
        'real_time': {**periods, 'nominal_rate_hz': 500},
        'goal_latency': {k: latency[k] for k in ('goal_to_first_motion_ms',)},
        'tracking': [tracking_error('ur5e'), tracking_error('ur10')],
        'tracking_target_mrad': 0.5,
    }


if __name__ == '__main__':
    import json
    out = Path(__file__).resolve().parents[1] / 'out' / 'bench'
    out.mkdir(parents=True, exist_ok=True)
    (out / 'sim.json').write_text(json.dumps(run(), indent=2))
