"""freedrive_mode_controller over DDS, with /ur_sim/apply_wrench pushing the arm: in freedrive the arm moves under
a push and stays where it was left (gravity compensated); under the same push the held robot does not move (a
position controller active, or freedrive_mode_controller active but not enabled); freedrive ends when the
messages stop (upstream's timeout) and when the controller is deactivated; messages to the inactive controller
are ignored."""
import time

import numpy as np
import pytest
from cm_helpers import ControllerManagerClient
from geometry_msgs.msg import WrenchStamped
from sim_harness import running_sim, wait_for, wait_still
from std_msgs.msg import Bool

NAME = 'freedrive_mode_controller'
SCALED = 'scaled_joint_trajectory_controller'
LINK = 'wrist_3_link'
PUSH = (0.0, 30.0, 0.0)  # [N] in the base frame, at the link's centre of mass
PUSH_TIME = 0.5  # [s]


@pytest.fixture(scope='module')
def rig():
    # In real time: a push's end is a simulated time, which must not pass while the message is on its way.
    with running_sim(real_time_factor=1.0) as h:
        cm = ControllerManagerClient(h)
        enable = h.client.create_publisher(Bool, f'/{NAME}/enable_freedrive_mode', 10)
        wrench = h.client.create_publisher(WrenchStamped, '/ur_sim/apply_wrench', 10)
        wait_still(lambda: enable.get_subscription_count() > 0, what='the freedrive subscriber')
        wait_still(lambda: wrench.get_subscription_count() > 0, what='the apply_wrench subscriber')
        freedrive = next(c for c in h.sim.components if c.name == NAME)
        yield h, cm, enable, wrench, freedrive


def push(h, wrench, force=PUSH, duration=PUSH_TIME) -> np.ndarray:
    """Push LINK for `duration` [s] of simulated time, wait until it ended and the arm settled; the joint motion."""
    q0 = h.q
    msg = WrenchStamped()
    msg.header.frame_id = LINK
    end = h.sim.sim.time + duration
    msg.header.stamp = h.sim.clock.stamp(end)
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = force
    wrench.publish(msg)
    wait_for(lambda: h.sim.sim.time > end + 1.0, what='the push and a second after it')
    return h.q - q0


def set_freedrive(h, enable, freedrive, on: bool) -> None:
    enable.publish(Bool(data=on))
    wait_for(lambda: freedrive.free == on, what=f'freedrive {on}')


def test_held_robot_resists_the_push(rig):
    h, cm, enable, wrench, freedrive = rig
    assert cm.states()[SCALED] == 'active'
    moved = push(h, wrench)
    assert np.abs(moved).max() < 1e-3, moved


def test_messages_to_the_inactive_controller_are_ignored(rig):
    h, cm, enable, wrench, freedrive = rig
    enable.publish(Bool(data=True))
    h.wait_sim_time(0.1)
    assert cm.switch(activate=[NAME], deactivate=[SCALED]).ok
    h.wait_sim_time(0.1)
    assert not freedrive.free
    # Active but not in freedrive: the robot holds where it is.
    moved = push(h, wrench)
    assert np.abs(moved).max() < 1e-3, moved


def in_charge(cm) -> None:
    """freedrive_mode_controller takes the joints (each test starts with the driver's controllers, conftest.py)."""
    assert cm.switch(activate=[NAME], deactivate=[SCALED]).ok


def test_freedrive_moves_under_the_push_and_stays(rig):
    h, cm, enable, wrench, freedrive = rig
    in_charge(cm)
    set_freedrive(h, enable, freedrive, True)
    enable.publish(Bool(data=True))
    moved = push(h, wrench)
    assert np.abs(moved).max() > 0.05, moved
    # Gravity compensated and damped: it comes to rest where the push left it, and does not sag.
    h.wait_sim_time(1.0)
    q = h.q
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q).max() < 2e-3
    assert np.abs(h.sim.sim.state().qd).max() < 0.01
    # Freedrive off: the same push no longer moves it.
    set_freedrive(h, enable, freedrive, False)
    moved = push(h, wrench, force=tuple(-f for f in PUSH))
    assert np.abs(moved).max() < 1e-3, moved


def test_freedrive_ends_when_the_messages_stop(rig):
    h, cm, enable, wrench, freedrive = rig
    in_charge(cm)
    freedrive.inactive_timeout = 0.5  # [s] of wall time (upstream's default is 10 s)
    try:
        # Not before the timeout: taken before the message is sent, so the bound holds however slow the machine
        # (the controller reads the same clock when the message arrives); how much later it ends is not bounded.
        t0 = time.monotonic()
        set_freedrive(h, enable, freedrive, True)
        wait_for(lambda: not freedrive.free, timeout=5.0, what='the timeout')
        assert time.monotonic() - t0 >= freedrive.inactive_timeout
    finally:
        freedrive.inactive_timeout = 10.0


def test_deactivation_ends_freedrive(rig):
    h, cm, enable, wrench, freedrive = rig
    in_charge(cm)
    set_freedrive(h, enable, freedrive, True)
    assert cm.switch(activate=[SCALED], deactivate=[NAME]).ok
    assert not freedrive.free
    moved = push(h, wrench)
    assert np.abs(moved).max() < 1e-3, moved
