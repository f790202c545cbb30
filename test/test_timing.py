"""Time law along the bead: rest-to-rest, exact cruise speed, smooth ramps, slowdowns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_glue_planner.path.timing import SpeedLimit, time_path

L, V, DT = 2.2, 0.15, 0.02


def numeric_derivative(timing, t: np.ndarray, h: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    s_p, v_p, _ = timing.evaluate(t + h)
    s_m, v_m, _ = timing.evaluate(t - h)
    return (s_p - s_m) / (2 * h), (v_p - v_m) / (2 * h)


@pytest.fixture(scope="module")
def plain():
    return time_path(L, V, DT, ramp_time=0.5)


def test_starts_and_ends_at_rest_on_the_sample_grid(plain):
    assert plain.times[0] == 0.0 and plain.s[0] == 0.0
    assert plain.s[-1] == L and plain.times[-1] == plain.duration
    np.testing.assert_allclose(np.diff(plain.times), DT, atol=1e-9)  # uniform, last one included
    assert plain.sdot[0] == pytest.approx(0.0, abs=1e-12) and plain.sdot[-1] == pytest.approx(0.0, abs=1e-12)
    assert plain.sddot[0] == pytest.approx(0.0, abs=1e-12) and plain.sddot[-1] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(plain.s) >= 0.0)


def test_duration_is_length_over_speed_plus_one_ramp(plain):
    # each quintic ramp covers v * T / 2, so the ramps cost T in total; rounded up to dt
    nominal = L / V + 0.5
    assert nominal <= plain.duration < nominal + DT + 1e-9
    assert plain.duration / DT == pytest.approx(round(plain.duration / DT), abs=1e-9)


def test_cruise_speed_is_exact(plain):
    cruise = (plain.times > 0.5 + DT) & (plain.times < plain.duration - 0.5 - DT)
    np.testing.assert_allclose(plain.sdot[cruise], V, rtol=0, atol=1e-12)
    np.testing.assert_allclose(plain.sddot[cruise], 0.0, atol=1e-12)
    assert cruise.sum() > 0.9 * len(plain.times)


def test_sdot_and_sddot_are_the_derivatives_of_s(plain):
    t = np.linspace(1e-4, plain.duration - 1e-4, 997)
    ds, dds = numeric_derivative(plain, t)
    s, sdot, sddot = plain.evaluate(t)
    np.testing.assert_allclose(ds, sdot, atol=1e-8)
    np.testing.assert_allclose(dds, sddot, atol=1e-6)


def test_ramps_are_smooth_and_bounded():
    timing = time_path(L, V, DT, ramp_time=0.5)
    # quintic ramp: peak 1.875 v / T; the end ramps are stretched by < dt, so slightly lower
    assert np.abs(timing.sddot).max() <= 1.875 * V / 0.5 + 1e-12
    assert np.abs(timing.sddot).max() > 1.875 * V / (0.5 + DT)
    t = np.linspace(0, 0.6, 601)
    _, _, sddot = timing.evaluate(t)
    assert np.max(np.abs(np.diff(sddot))) < 0.01  # no step in the acceleration
    assert np.all(timing.sdot <= V + 1e-12)


def test_a_slowdown_holds_its_speed_over_its_window_and_changes_outside():
    lim = SpeedLimit(1.0, 1.1, 0.6)
    timing = time_path(L, V, DT, ramp_time=0.5, limits=[lim])
    s, sdot, _ = timing.evaluate(np.linspace(0, timing.duration, 20001))
    inside = (s >= 1.0) & (s <= 1.1)
    np.testing.assert_allclose(sdot[inside], 0.6 * V, atol=1e-12)
    assert sdot[(s > 0.3) & (s < 0.9)].max() == pytest.approx(V)
    assert ((1.0, 1.1, pytest.approx(0.6 * V)) in [(a, b, c) for a, b, c in timing.levels])
    # the extra time is the window at 0.6 v plus the two speed changes (each ramp_time * 0.4 long)
    extra = 0.1 / (0.6 * V) - 0.1 / V + 2 * 0.5 * 0.4 * (1 - 0.8) / 1.0
    assert timing.duration == pytest.approx(L / V + 0.5 + extra, abs=DT + 1e-6)


def test_overlapping_slowdowns_take_the_lower_factor():
    timing = time_path(L, V, DT, limits=[SpeedLimit(1.0, 1.2, 0.8), SpeedLimit(1.1, 1.3, 0.5)])
    s, sdot, _ = timing.evaluate(np.linspace(0, timing.duration, 20001))
    assert sdot[(s > 1.1) & (s < 1.2)].max() == pytest.approx(0.5 * V)
    assert sdot[(s > 1.0) & (s < 1.09)].max() == pytest.approx(0.8 * V)


def test_a_short_path_never_reaches_the_speed_but_still_ends_at_rest():
    timing = time_path(0.03, V, DT, ramp_time=0.5)
    assert timing.s[-1] == 0.03 and timing.sdot[-1] == pytest.approx(0.0, abs=1e-12)
    assert 0.0 < timing.sdot.max() < V
    # rest to peak c and back, each ramp c^2 T / (2 v) long: c = sqrt(L v / T)
    assert timing.sdot.max() == pytest.approx(math.sqrt(0.03 * V / 0.5), rel=0.05)
    assert np.all(np.diff(timing.times) > 0.5 * DT - 1e-12)


def test_usage_makes_speed_changes_gentle_where_the_joints_need_it():
    def usage(s, sdot, sddot):
        # a stand-in for joint limits: tangential acceleration above 0.1 m/s^2 overloads 0.8..1.2 m
        return np.where((s > 0.8) & (s < 1.2), np.abs(sddot) / 0.1, np.abs(sddot) / 100.0)

    timing = time_path(L, V, DT, ramp_time=0.5, limits=[SpeedLimit(1.0, 1.1, 0.5)], usage=usage)
    s, _, sddot = timing.evaluate(np.linspace(0, timing.duration, 40001))
    assert np.abs(sddot[(s > 0.8) & (s < 1.2)]).max() <= 0.1 + 1e-9
    assert np.abs(sddot).max() > 0.5  # the end ramps keep their nominal steepness


def test_evaluate_clamps_and_takes_scalars(plain):
    s, sdot, sddot = plain.evaluate(-1.0)
    assert (s, sdot, sddot) == (0.0, 0.0, 0.0)
    s, sdot, _ = plain.evaluate(plain.duration + 5.0)
    assert s == pytest.approx(L) and sdot == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("kwargs", [{"length": 0.0}, {"speed": -1.0}, {"dt": math.nan}, {"ramp_time": 0.0},
                                    {"limits": [SpeedLimit(0.1, 0.2, 1.5)]}, {"limits": [SpeedLimit(0.3, 0.2, 0.5)]}])
def test_bad_arguments_raise(kwargs):
    args = {"length": L, "speed": V, "dt": DT, **kwargs}
    with pytest.raises(ValueError):
        time_path(**args)
