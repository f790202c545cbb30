"""The stamps' clock. The real driver stamps with the system clock; ur_sim in real time does too (simulated time
counted from the wall clock at start), so a client without use_sim_time can look up /tf at its own now. Otherwise
(as fast as possible, in step with a client) simulated time counts from 0 and clients use /clock. Either way a
stamp a client sends is read on the same clock as the stamps it receives.
"""
import time

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Time
from control_msgs.srv import QueryTrajectoryState
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from sim_harness import point, running_sim, wait_for, wait_still
from tf2_msgs.msg import TFMessage

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.motion.conversions import RobotClock

ORIGIN = 1_795_000_000_123_456_789  # [ns] a system clock's time


def ns(stamp: Time) -> int:
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def test_robot_clock_maps_simulated_time_to_stamps_and_back():
    clock = RobotClock(ORIGIN)
    assert clock.parts(0.0) == (1_795_000_000, 123_456_789)
    assert clock.parts(2.5) == (1_795_000_002, 623_456_789)
    assert clock.sim_time(clock.stamp(2.5)) == pytest.approx(2.5, abs=1e-12)
    # A stamp before the origin is in the simulation's past; zero means "now" / "no end" on both sides.
    assert clock.sim_time(Time(sec=1_794_999_999, nanosec=123_456_789)) == pytest.approx(-1.0, abs=1e-12)
    assert clock.sim_time(Time()) == 0.0
    assert clock.sim_seconds(0.0) == 0.0
    assert clock.sim_seconds(1_795_000_001.123456789) == pytest.approx(1.0, abs=1e-6)  # float seconds: ~0.24 us
    assert RobotClock().parts(1.25) == (1, 250_000_000)
    assert RobotClock().sim_time(Time(sec=3, nanosec=500_000_000)) == 3.5


def test_in_real_time_the_stamps_are_the_system_clock():
    # The wall clock is the subject. A stamp is never before the node was made (its origin is taken then) and never
    # more than one control period ahead of its receipt (a cycle is published when its period starts); a loaded
    # machine only makes the stamps later, never outside these bounds.
    before = time.time_ns()
    with running_sim(real_time_factor=1.0) as h:
        states, clocks, tcp = [], [], []
        h.listen(JointState, '/joint_states', lambda m: states.append(ns(m.header.stamp)))
        h.listen(Clock, '/clock', lambda m: clocks.append(ns(m.clock)))
        h.listen(TFMessage, '/tf', lambda m: tcp.extend(ns(t.header.stamp) for t in m.transforms
                                                        if t.child_frame_id == 'tool0_controller'))
        wait_for(lambda: len(states) >= 50 and len(clocks) >= 50 and clocks[-1] > states[0] and states[-1] > clocks[0]
                 and tcp, what='joint states, /clock messages of the same cycles and the TCP on /tf')
        received = time.time_ns()
        period = round(h.sim.sim.control_dt * 1e9)
        assert before <= states[0] and states[-1] <= received + period
        assert before <= tcp[0] and tcp[-1] <= received + period  # what a tf lookup at the client's now needs
        assert np.all(np.diff(states) > 0)
        # /clock carries the same time as the stamps (use_sim_time clients see the same clock).
        common = set(states) & set(clocks)
        assert common, 'no /clock message has the time of a joint state'


@pytest.fixture(scope='module')
def on_system_clock():
    # In lockstep, but with the origin of real time (real_time_factor 1.0): deterministic, and stamped as the driver.
    with running_sim(lockstep=True, real_time_factor=1.0) as h:
        yield h


def newest_stamp(h) -> int:
    """The newest joint state's stamp [ns], as a client sees it."""
    seen = []
    stop = h.listen(JointState, '/joint_states', lambda m: seen.append(ns(m.header.stamp)))
    try:
        wait_for(lambda: seen, what='a joint state')
        return seen[-1]
    finally:
        stop()


def test_a_goal_stamped_on_the_robots_clock_ends_at_its_stamp(on_system_clock):
    # As upstream's JTC, the arm heads for the first point from where the goal found it, arriving at header.stamp +
    # time_from_start: the target is reached half a second of robot time after the stamp, not after the arrival.
    h = on_system_clock
    origin = h.sim.clock.origin_ns
    assert origin > 1_700_000_000 * 10**9  # the wall clock when the node was made
    start = newest_stamp(h) + 500_000_000  # half a second of robot time ahead
    target = h.q + 0.1
    goal = h.goal([point(target, 0.5, np.zeros(6))])
    goal.trajectory.header.stamp = Time(sec=start // 10**9, nanosec=start % 10**9)
    h.record()
    handle = h.send(goal)
    assert handle.accepted
    assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    t, q, _ = h.stop_recording().arrays()  # stamps as simulated time
    t_end = (start - origin) * 1e-9 + 0.5  # the stamp in simulated time, plus the point's time_from_start
    there = np.abs(q - target).max(axis=1) < 1e-3
    assert there.any()
    assert t_end - 0.1 <= t[there][0] <= t_end + 0.1, (t[there][0], t_end)  # 0.94 s, as the spline flattens


def test_a_goal_that_ended_before_the_robots_now_is_rejected(on_system_clock):
    h = on_system_clock
    start = newest_stamp(h) - 2_000_000_000  # 2 s ago, 1 s long
    goal = h.goal([point(h.q + 0.1, 1.0, np.zeros(6))])
    goal.trajectory.header.stamp = Time(sec=start // 10**9, nanosec=start % 10**9)
    handle = h.send(goal)
    assert not handle.accepted


def test_query_state_reads_its_time_on_the_robots_clock(on_system_clock):
    h = on_system_clock
    # Left to the harness's teardown: entities are not destroyed under a spinning executor.
    query = h.client.create_client(QueryTrajectoryState, '/scaled_joint_trajectory_controller/query_state')
    wait_still(query.service_is_ready, what='query_state')
    q0 = h.q
    handle = h.send(h.goal([point(q0 + 0.2, 2.0, np.zeros(6))]))
    assert handle.accepted
    try:
        at = newest_stamp(h) + 1_000_000_000
        future = query.call_async(QueryTrajectoryState.Request(time=Time(sec=at // 10**9, nanosec=at % 10**9)))
        wait_still(future.done, what='the query_state answer')
        answer = future.result()
        assert answer.success, answer.message
        # 1 s later on a 2 s trajectory from q0 to q0 + 0.2: between the two, not at either end.
        position = np.asarray(answer.position)
        assert np.all(position > q0 + 0.01) and np.all(position < q0 + 0.19)
    finally:
        h.result(handle)
