"""The glue gun's switch times: lead and lag from the delays and the timed path, and the bead they lay under
the gun's documented model (dead time, then first-order flow) is uniform, closure included."""
from __future__ import annotations

import numpy as np
import pytest

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.job import parse_job
from ur_glue_planner.motion.dispense import run_up_length, schedule_dispenser, time_at

SPEC = parse_job({}).dispenser
V = 0.15


def flow(t: np.ndarray, t_on: float, t_off: float, on_delay: float, off_delay: float, tau: float) -> np.ndarray:
    """Share of the rate at times t: the valve opens at t_on + on_delay, closes at t_off + off_delay."""
    t_open, t_close = t_on + on_delay, t_off + off_delay
    rise = np.where(t >= t_open, 1.0 - np.exp(-(t - t_open) / tau), 0.0)
    at_close = 1.0 - np.exp(-(t_close - t_open) / tau)
    return np.where(t < t_close, rise, at_close * np.exp(-(t - t_close) / tau))


def test_time_at_interpolates_and_refuses_beyond_the_end():
    times, s = np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.0, 0.3])  # at rest first, then moving
    assert time_at(times, s, 0.0) == 0.0
    assert time_at(times, s, 0.15) == pytest.approx(1.5)
    with pytest.raises(PlanningError, match='ends at s'):
        time_at(times, s, 0.4)


def test_lead_and_lag_on_a_constant_speed_path():
    times = np.arange(0.0, 20.0, 0.02)
    s = V * times
    d = schedule_dispenser(SPEC, times, s, np.full(len(s), V), 0.06, 2.06, V)
    assert d.t_arrive == pytest.approx(0.4) and d.t_leave == pytest.approx(2.06 / V)
    assert d.lead == pytest.approx(SPEC.on_delay + SPEC.time_constant)
    assert d.lag == pytest.approx(SPEC.off_delay + SPEC.time_constant)
    assert d.t_on == pytest.approx(0.4 - d.lead) and d.t_off == pytest.approx(2.06 / V - d.lag)
    assert d.speed_start == pytest.approx(V) and d.nominal_area == pytest.approx(SPEC.flow_rate / V)
    with pytest.raises(PlanningError, match='empty'):
        schedule_dispenser(SPEC, times, s, np.full(len(s), V), 0.5, 0.5, V)


def test_the_scheduled_flow_lays_a_uniform_closed_bead():
    loop = 1.0  # [m]
    run_up = run_up_length(SPEC, V, 0.3)
    dt = 1.0 / 15000.0  # 0.01 mm of path per step: 100 steps per 1 mm bin
    t = np.arange(0.0, (loop + 2 * run_up) / V, dt)
    s = V * t
    d = schedule_dispenser(SPEC, t, s, np.full(len(s), V), run_up, run_up + loop, V)
    q = flow(t, d.t_on, d.t_off, SPEC.on_delay, SPEC.off_delay, SPEC.time_constant)
    # material per station of the loop (1 mm bins), both passes over the closure added
    station = np.mod(s - run_up, loop)
    bins = np.floor(station / 0.001 + 1e-6).astype(int) % 1000
    area = np.bincount(bins, weights=q * dt, minlength=1000)[:1000] / (0.001 / V)
    assert np.abs(area - 1.0).max() < 0.01  # the start's rise and the end's fall add up to the full bead
    # without the lead's time constant the same switching would leave a dip at the closure
    q_late = flow(t, d.t_on + SPEC.time_constant, d.t_off, SPEC.on_delay, SPEC.off_delay, SPEC.time_constant)
    late = np.bincount(bins, weights=q_late * dt, minlength=1000)[:1000] / (0.001 / V)
    assert late.min() < 0.8


def test_run_up_covers_the_ramp_and_the_flow_transients():
    assert run_up_length(SPEC, V, 0.3) == pytest.approx(V * (0.15 + 4 * SPEC.time_constant) + 0.005)
