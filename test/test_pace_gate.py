"""PaceGate over DDS: the robot time a client publishes on the pace topic, on the stamps' clock, holds the loop."""
import threading

import pytest
from builtin_interfaces.msg import Time
from rclpy.node import Node
from ros_helpers import executor_with, ros_context, spin_until
from rosgraph_msgs.msg import Clock

from ur_sim_driver.motion.conversions import RobotClock
from ur_sim_driver.ros.pace_gate import PACE_QOS, PaceGate

TOPIC = '/ur_sim/pace'
ORIGIN = 1_795_000_000_000_000_000  # [ns] ur_sim in real time: stamps on the system clock
LAG = 0.01  # [s]
DT = 0.002  # [s]


def stamp(t: float) -> Clock:
    ns = ORIGIN + round(t * 1e9)
    return Clock(clock=Time(sec=ns // 10**9, nanosec=ns % 10**9))


@pytest.fixture
def gate_and_client():
    with ros_context() as ctx:
        sim, client = Node('pace_gate_sim', context=ctx), Node('pace_gate_client', context=ctx)
        gate = PaceGate(sim, TOPIC, RobotClock(ORIGIN), LAG)
        publisher = client.create_publisher(Clock, TOPIC, PACE_QOS)
        with executor_with(ctx, sim, client) as executor:
            yield gate, publisher, executor


def test_the_clients_time_is_read_on_the_stamps_clock(gate_and_client):
    gate, publisher, executor = gate_and_client
    assert gate.paced_until is None
    publisher.publish(stamp(1.25))
    spin_until(executor, lambda: gate.paced_until is not None, 10.0, 'the pace message')
    assert gate.paced_until == pytest.approx(1.25, abs=1e-9)
    # The newest counts, also an earlier one: a client may hold the simulation back.
    publisher.publish(stamp(1.0))
    spin_until(executor, lambda: gate.paced_until < 1.1, 10.0, 'the earlier pace message')


def test_the_loop_waits_past_the_lag_until_the_client_catches_up(gate_and_client):
    gate, publisher, executor = gate_and_client
    stop = threading.Event()
    gate.wait(5.0, DT, stop)  # before the client's first message: one period, then on
    publisher.publish(stamp(1.0))
    spin_until(executor, lambda: gate.paced_until is not None, 10.0, 'the pace message')
    gate.wait(1.0 + LAG, DT, stop)  # within the lag: no wait
    waiter = threading.Thread(target=gate.wait, args=(1.0 + 2 * LAG, DT, stop), name='held_loop')
    waiter.start()
    try:
        waiter.join(0.2)
        assert waiter.is_alive(), 'the loop ran past the client by more than the lag'
        publisher.publish(stamp(1.0 + LAG))  # the client caught up: the loop goes on
        spin_until(executor, lambda: not waiter.is_alive(), 10.0, 'the loop to go on')
    finally:
        stop.set()  # a held loop sees a stop within STOP_POLL
        waiter.join(10.0)
    assert not waiter.is_alive()
