"""What ur_sim accepts and how: 100,000-point trajectories, start stamps far ahead, the strict limit checks."""
import time
from pathlib import Path

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from control_msgs.msg import SpeedScalingFactor
from rcl_interfaces.msg import Log
from sim_harness import point, running_sim, trajectory, wait_for
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ur_sim_driver.motion import result_codes as rc

N = 100_000


def long_trajectory(names, q0, n=N, dt=0.001) -> JointTrajectory:
    """n points, dt apart [s], a slow sine on the first joint (velocities given: cubic segments)."""
    t = dt * np.arange(1, n + 1)
    q = np.tile(q0, (n, 1))
    q[:, 0] += 0.1 * np.sin(2 * np.pi * t / (n * dt))
    qd = np.zeros_like(q)
    qd[:, 0] = 0.1 * 2 * np.pi / (n * dt) * np.cos(2 * np.pi * t / (n * dt))
    qd[-1] = 0.0
    points = []
    for k in range(n):
        p = JointTrajectoryPoint(positions=q[k].tolist(), velocities=qd[k].tolist())
        ns = round(t[k] * 1e9)
        p.time_from_start.sec, p.time_from_start.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        points.append(p)
    return JointTrajectory(joint_names=list(names), points=points)


@pytest.fixture(scope='module')
def h():
    # Free-running: the subject is the simulation going on while another process takes a long trajectory in.
    with running_sim(lockstep=False) as harness:
        yield harness


def test_a_100k_point_goal_is_accepted_and_runs(h):
    goal = h.goal([])
    goal.trajectory = long_trajectory(h.joints, h.q)
    t_sim = h.sim.sim.time
    handle = h.send(goal)
    assert handle.accepted
    wait_for(lambda: h.sim.jtc.trajectory is not None and len(h.sim.jtc.trajectory.points.times) == N,
             what='the long trajectory to start')
    assert h.sim.sim.time > t_sim  # the simulation went on meanwhile
    h.wait_sim_time(0.5)
    wait_for(handle.cancel_goal_async().done, what='the cancel')
    assert h.result(handle)[0] == GoalStatus.STATUS_CANCELED
    assert h.sim.jtc.trajectory is None  # dropped: its memory goes with it


def test_speed_scaling_sent_behind_a_100k_point_message_applies_and_the_message_runs(h):
    # The long message goes to the controller's interface process; the factor is served by the simulation
    # process. How soon the factor applies while the long message is read is bench_intake's
    # (`make bench`: topic.speed_scaling_applied_ms), not asserted here: it is a race between the two.
    msg = long_trajectory(h.joints, h.q)
    h.topic.publish(msg)
    h.scaling.publish(SpeedScalingFactor(factor=0.3))
    wait_for(lambda: h.sim.jtc.speed_scaling == 0.3, what='the factor')
    wait_for(lambda: h.sim.jtc.trajectory is not None and len(h.sim.jtc.trajectory.points.times) == N,
             what='the long topic trajectory to start')
    h.scaling.publish(SpeedScalingFactor(factor=1.0))
    q = h.q
    h.topic.publish(trajectory(h.joints, [point(q, 0.5, np.zeros(6))]))
    wait_for(lambda: h.sim.jtc.trajectory is None or len(h.sim.jtc.trajectory.points.times) == 1,
             what='the replacement')


def rss_mb(pid: int) -> float:
    """Resident memory of process `pid` [MB]."""
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0
    raise ValueError(f'no VmRSS for process {pid}')


def test_the_controller_process_gives_a_long_goals_and_messages_memory_back(h):
    # The process that takes goals and messages (gateway_process.py) reads them into arrays, hands them over
    # and lets go: no pool of receive buffers, no heap that keeps what the points took.
    gateway = h.sim.gateway.process.pid
    before = rss_mb(gateway)
    goal = h.goal([])
    goal.trajectory = long_trajectory(h.joints, h.q)
    handle = h.send(goal)
    assert handle.accepted
    del goal
    wait_for(lambda: h.sim.jtc.trajectory is not None and len(h.sim.jtc.trajectory.points.times) == N,
             what='the long trajectory to start')
    wait_for(handle.cancel_goal_async().done, what='the cancel')
    assert h.result(handle)[0] == GoalStatus.STATUS_CANCELED
    h.topic.publish(long_trajectory(h.joints, h.q))
    wait_for(lambda: h.sim.jtc.trajectory is not None and len(h.sim.jtc.trajectory.points.times) == N,
             what='the long topic trajectory to start')
    h.topic.publish(trajectory(h.joints, [point(h.q, 0.5, np.zeros(6))]))
    wait_for(lambda: h.sim.jtc.trajectory is None or len(h.sim.jtc.trajectory.points.times) == 1,
             what='the replacement')
    # Within 20 MB of before (issue #9); it was 60 MB more before the goal intake and the reader profile.
    end = time.monotonic() + 10.0  # it trims its heap once more 1 s after a goal
    while rss_mb(gateway) - before >= 20.0 and time.monotonic() < end:
        time.sleep(0.1)
    kept = rss_mb(gateway) - before
    assert kept < 20.0, f'the controller process kept {kept:.1f} MB'


def test_a_start_far_ahead_is_accepted_and_said(h):
    logs = []
    h.listen(Log, '/rosout', lambda m: logs.append(m.msg), latched=True)  # the gateway's lines, from its start
    goal = h.goal([point(h.q, 1.0, np.zeros(6))])
    stamp = h.sim.sim.time + 100.0
    goal.trajectory.header.stamp.sec = int(stamp)
    handle = h.send(goal)
    assert handle.accepted
    wait_for(lambda: any(f'{int(stamp)}.000 s' in text for text in logs), what='the line on /rosout')
    line = next(text for text in logs if f'{int(stamp)}.000 s' in text)
    # a start on the simulated clock, only far ahead: no clock is blamed
    assert 'simulated time now' in line and 'waits until then' in line and 'use_sim_time' not in line
    wait_for(handle.cancel_goal_async().done, what='the cancel')
    assert h.result(handle)[0] == GoalStatus.STATUS_CANCELED


def test_a_wall_clock_start_is_accepted_with_a_warning_naming_use_sim_time(h):
    logs = []
    h.listen(Log, '/rosout', lambda m: logs.append(m.msg), latched=True)  # the gateway's lines, from its start
    goal = h.goal([point(h.q, 1.0, np.zeros(6))])
    wall = int(time.time())  # a client on the wall clock while ur_sim runs on simulated time
    goal.trajectory.header.stamp.sec = wall
    handle = h.send(goal)
    assert handle.accepted
    wait_for(lambda: any(f'{wall}.000 s' in text for text in logs), what='the warning on /rosout')
    line = next(text for text in logs if f'{wall}.000 s' in text)
    assert 'use_sim_time:=true' in line
    wait_for(handle.cancel_goal_async().done, what='the cancel')
    assert h.result(handle)[0] == GoalStatus.STATUS_CANCELED


def test_strict_limit_checks_reject_what_the_driver_accepts():
    # Its own namespace: the module's simulator serves the default names meanwhile.
    with running_sim(strict_limit_checks=True, namespace='strict') as strict:
        q = strict.q
        outside = q.copy()
        outside[2] = 4.0  # elbow limit +-pi
        assert not strict.send(strict.goal([point(outside, 2.0)])).accepted
        fast = strict.goal([point(q, 0.1), point(q + np.array([1.0, 0, 0, 0, 0, 0]), 0.15, np.zeros(6))])
        assert not strict.send(fast).accepted
        assert np.abs(strict.q - q).max() < 1e-3
        ok = strict.send(strict.goal([point(q, 0.2, np.zeros(6))]))
        assert ok.accepted and strict.result(ok)[1] == rc.SUCCESSFUL
