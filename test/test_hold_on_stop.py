"""The robot when no controller commands it any more.

Switched off mid-motion (switch_controller with no replacement), the driver writes keepalives (MODE_IDLE) and the
External Control program ends its servo thread with stopj(4.0): the arm decelerates, linear in joint space with the
leading joint at 4 rad/s^2, and holds where it comes to rest, not back where the controller left off.
"""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import ControllerManagerClient
from sim_harness import point, running_sim, wait_for

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.robot.direct_torque import STOPJ_DECELERATION
from ur_sim_driver.robot.robot_state import NORMAL

pytestmark = pytest.mark.timeout(300)
SCALED = 'scaled_joint_trajectory_controller'
SPEED = np.array([0.5, 0.0, 0.0, 0.0, 0.0, 0.25])  # [rad/s] shoulder_pan leads, wrist_3 at half its speed


def _at_rest(h, rec) -> bool:
    """0.1 s of joint states reporting exactly 0 velocity: at rest, not passing through 0."""
    cycles = round(0.1 / h.sim.sim.control_dt)
    return len(rec.qd) > cycles and not np.any(rec.qd[-cycles:])


def test_a_controller_switched_off_mid_motion_brakes_as_stopj_and_holds_where_it_comes_to_rest():
    with running_sim() as h:
        cm = ControllerManagerClient(h)
        try:
            # Linear interpolation to a point 4 s away: constant joint speeds once the servo has taken them up.
            handle = h.send(h.goal([point(h.q + 4.0 * SPEED, 4.0)]))
            assert handle.accepted
            h.wait_sim_time(1.0)
            rec = h.record()
            assert cm.switch(deactivate=[SCALED]).ok
            status, code, text = h.result(handle)
            assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL), text
            wait_for(lambda: _at_rest(h, rec), timeout=2.0, what='the arm at rest')
            h.stop_recording()
            t, q, qd = rec.arrays()
            # The switch takes effect between two cycles: the last sample at full speed is where braking begins.
            moving = np.flatnonzero(qd[:, 0] >= 0.99 * SPEED[0])
            assert moving.size, qd[:, 0]
            k = int(moving[-1])
            v0, q0 = qd[k], q[k]
            assert np.allclose(v0, SPEED, atol=0.01), v0
            rest = q[-1]
            travel = rest - q0
            # stopj: the leading joint stops after v^2 / (2 a), in v / a; the others in the same time, on the line.
            expected = v0[0] ** 2 / (2.0 * STOPJ_DECELERATION)
            assert travel[0] == pytest.approx(expected, rel=0.05), (travel, expected)
            assert travel[5] / travel[0] == pytest.approx(SPEED[5] / SPEED[0], abs=0.02), travel
            assert np.abs(travel[1:5]).max() < 1e-3, travel
            stopped = t[np.flatnonzero(np.any(qd, axis=1))[-1] + 1] - t[k]  # reporting 0 from then on
            assert stopped == pytest.approx(v0[0] / STOPJ_DECELERATION, abs=0.02), stopped
            assert np.all(qd[k:, 0] >= 0.0) and np.all(qd[k:, 5] >= 0.0)  # no turning back
            h.wait_sim_time(0.5)
            assert np.abs(h.q - rest).max() < 1e-5  # held there
        finally:
            if cm.states()[SCALED] != 'active':
                assert cm.switch(activate=[SCALED]).ok


def test_an_arm_switched_off_short_of_its_limit_rests_at_it_and_moves_away_again():
    # Braking at 4 rad/s^2 from 0.5 rad/s takes 31 mrad, the limit is 15 mrad ahead: the robot stops at its limit
    # (the servo brakes harder for a limit), with no protective stop, and a controller activated there moves it away.
    limit = 2.0 * np.pi
    with running_sim() as h:
        cm = ControllerManagerClient(h)
        try:
            start = h.q.copy()
            start[5] = limit - 0.6
            assert h.result(h.send(h.goal([point(start, 3.0, [0.0] * 6)])))[1] == rc.SUCCESSFUL
            end = start.copy()
            end[5] = limit
            handle = h.send(h.goal([point(end, 1.2)]))  # 0.5 rad/s
            assert handle.accepted
            wait_for(lambda: h.q[5] > limit - 0.015, what='wrist_3 15 mrad short of its limit')
            assert cm.switch(deactivate=[SCALED]).ok
            rec = h.record()
            wait_for(lambda: _at_rest(h, rec), timeout=2.0, what='the arm at rest')
            h.stop_recording()
            assert abs(h.q[5] - limit) < 1e-3  # at the limit (the braked arm may lie microradians past it)
            assert h.sim.robot.safety_mode == NORMAL, h.sim.robot.stop_cause
            assert cm.switch(activate=[SCALED]).ok
            back = h.send(h.goal([point(start, 2.0, [0.0] * 6)]))
            assert h.result(back)[1] == rc.SUCCESSFUL
            assert h.sim.robot.safety_mode == NORMAL, h.sim.robot.stop_cause
        finally:
            if cm.states()[SCALED] != 'active':
                assert cm.switch(activate=[SCALED]).ok
