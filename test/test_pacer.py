"""The paced simulation of the harness (sim_harness.Pacer): robot time runs at the wall clock's pace, stands still
while a message travels to ur_sim, and waits for a followed client that lags."""
import threading
import time

import numpy as np
import pytest
from sim_harness import point, running_sim, trajectory, wait_for

DELAY = 0.5  # [s] of wall time a message is held back, as a loaded machine's DDS delivery can (3 s seen)


@pytest.fixture(scope='module')
def h():
    with running_sim(paced=True, ur_type='ur5e') as harness:
        yield harness


def test_a_late_message_arrives_at_the_simulated_time_it_was_sent(h):
    q0 = h.q.copy()
    target = q0 + np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.0])
    msg = trajectory(h.joints, [point(target, 0.5)])
    publish = h.topic._publisher.publish
    try:
        # The message leaves DELAY after publish() is called, as a DDS sample lost once and sent again does.
        h.topic._publisher.publish = lambda m: threading.Timer(DELAY, publish, args=(m,)).start()
        sent = h.sim.sim.time
        h.topic.publish(msg)  # returns once ur_sim has it: held still meanwhile
        # A cycle may begin between reading the clock and the hold; unheld, DELAY would be 250 cycles.
        assert h.sim.sim.time - sent <= h.sim.sim.control_dt + 1e-9
    finally:
        h.topic._publisher.publish = publish
    wait_for(lambda: np.abs(h.q - target).max() < 1e-3, what='the target')


def test_a_followed_client_that_lags_stops_the_clock_until_it_catches_up(h):
    seen = [h.sim.sim.time - h.sim.sim.control_dt]  # a client that has seen every cycle so far, then nothing more
    view = lambda: seen[0]  # noqa: E731
    h.pacer.follow(view)
    try:
        # Watched over 0.3 s of wall time, 150 cycles at real time's pace: the clock stays within LAG of the view.
        time.sleep(0.3)
        assert h.sim.sim.time <= seen[0] + h.pacer.LAG + 2 * h.sim.sim.control_dt + 1e-9
        stopped = h.sim.sim.time
        seen[0] = float('inf')  # caught up: the clock runs again
        wait_for(lambda: h.sim.sim.time >= stopped + 0.1, what='the clock running again')
    finally:
        h.pacer.unfollow(view)
