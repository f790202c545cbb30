"""robot/encoders.py: joint velocities as the robot's controller reports them (whole encoder ticks per control
period), and over DDS: a joint brought to rest reports exactly 0.0 within 0.1 s of its motion's end, and from then
on."""
from __future__ import annotations

import math

import numpy as np
import pytest
from sim_harness import point, running_sim

from ur_sim_driver.robot.encoders import TICK, reported_velocity, velocity_step

ZERO = [0.0] * 6


def test_the_reported_velocity_is_whole_ticks_per_period():
    dt = 0.002
    step = velocity_step(dt)
    assert step == pytest.approx(2 * math.pi / 2**20 / dt) and TICK / dt == step
    qd = np.array([0.0, 0.49 * step, 0.51 * step, -2.6 * step, 1.0, -1e-9])
    out = reported_velocity(qd, dt)
    np.testing.assert_array_equal(out, [0.0, 0.0, step, -3 * step, round(1.0 / step) * step, 0.0])
    assert not np.signbit(out[5])  # 0.0, not -0.0
    assert np.all(np.abs(out - qd) <= step / 2)
    assert velocity_step(0.008) == pytest.approx(velocity_step(0.002) / 4)  # a CB3's period: finer steps


@pytest.mark.parametrize('ur_type', ['ur5e', 'ur10'])
def test_a_joint_at_rest_reports_exactly_zero_velocity(ur_type):
    """After a trajectory to rest, /joint_states velocity is 0.0 on every joint from 0.1 s after the result on
    (the simulated joints still creep at 1e-4 rad/s then), through a 1 s hold; a CB3 settles slowest."""
    with running_sim(ur_type=ur_type) as h:
        h.record()
        goal = h.send(h.goal([point(h.q + np.array([0.3, -0.2, 0.25, 0.1, -0.1, 0.2]), 1.5, ZERO)]))
        assert goal.accepted and h.result(goal)[1] == 0
        end = h.sim.sim.time
        h.wait_sim_time(1.0)
        t, _, qd = h.stop_recording().arrays()
        moving = t < end - 0.2
        assert np.abs(qd[moving]).max() > 0.1  # it did move, and was reported moving
        rest = t >= end + 0.1
        assert rest.sum() >= 0.9 * h.sim.sim.control_rate
        assert np.all(qd[rest] == 0.0), qd[rest][qd[rest] != 0.0]
        assert np.abs(h.sim.sim.state().qd).max() > 0.0  # the physics alone never gets there
