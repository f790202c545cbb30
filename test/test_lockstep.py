"""The lockstep simulation of the harness (sim_harness.Lockstep): a followed listener sees every message of every
cycle however slowly it takes them, because the simulation waits for it."""
import time

import numpy as np
import pytest
from sensor_msgs.msg import JointState
from sim_harness import following, running_sim, wait_for

from ur_sim_driver.motion import conversions as conv

SLOW = 0.002  # [s] of wall time a listener spends on each message: slower than a cycle is stepped, as under load
DEPTH = 100  # its queue, over Lockstep.LAG_CYCLES: without following, it overflows within 200 cycles


@pytest.fixture(scope='module')
def h():
    with running_sim(ur_type='ur5e') as harness:
        yield harness


def test_a_followed_slow_listener_misses_no_cycle(h):
    stamps: list[float] = []

    def slow(msg: JointState) -> None:
        time.sleep(SLOW)  # a stand-in for a loaded machine, not a synchronisation
        stamps.append(conv.time_to_sec(msg.header.stamp))

    stop = h.listen(JointState, '/joint_states', slow, depth=DEPTH)
    try:
        with following(lambda: stamps[-1] if stamps else None):
            # Until its first message a listener is not followed (the cycles before its subscription matched are not
            # its to see): wait for it, then measure from the cycles it is followed in.
            wait_for(lambda: stamps, what='the first joint state at the listener')
            h.wait_sim_time(0.02)
            first = len(stamps)
            h.wait_sim_time(1.0)  # 500 cycles, five times the queue
    finally:
        stop()
    received = np.array(stamps[first:])
    assert len(received) >= 490  # the listener kept within Lockstep.LAG_CYCLES of the 500
    assert np.allclose(np.diff(received), h.sim.sim.control_dt, atol=1e-9), 'a cycle was lost'
