"""The dispenser model against hand-computed flows and cross-sections."""
from __future__ import annotations

import math

import numpy as np
import pytest

from ur_sim_driver.description.bead import ASPECT, section
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.dispenser import POINT_SPACING, BeadTrack, DispenserParams, FlowState, flow_step

DT = 0.002  # [s] e-series control period
STEADY = DispenserParams(on_delay=0.0, off_delay=0.0, time_constant=0.0)  # flow = rate while on


def lay(params: DispenserParams, xs, output) -> tuple[BeadTrack, np.ndarray]:
    """Run the model over cycles k = 0..K-1 (t = k DT) with the tip over the surface point (xs[k], 0, 0) and
    the output output[k], as the simulator does. Returns the track and the flow share at every cycle."""
    track = BeadTrack(params.nozzle)
    state, flows = FlowState(), []
    for k, (x, on) in enumerate(zip(xs, output)):
        was_idle = state.idle
        state, volume = flow_step(params, state, k * DT, bool(on))
        if not (was_idle and state.idle):
            track.add(k * DT, np.array([x, 0.0, 0.0]), volume)
        if state.idle:
            track.end_run()
        flows.append(state.flow)
    return track, np.array(flows)


def track_at(speeds) -> np.ndarray:
    """Tip positions [m] at the cycles, starting at 0, moving at speeds[k] [m/s] during cycle k."""
    return np.r_[0.0, np.cumsum(np.asarray(speeds) * DT)]


def test_section_is_the_triangle() -> None:
    w, h = section(40e-6)  # 40 mm^2
    assert w * h / 2 == pytest.approx(40e-6) and h / w == pytest.approx(ASPECT)
    assert w == pytest.approx(math.sqrt(2 * 40e-6 / 1.2))


def test_constant_speed_gives_flow_over_speed() -> None:
    k = 600
    track, _ = lay(STEADY, track_at([0.15] * k), [True] * (k + 1))
    bead = track.bead()
    area = 6e-6 / 0.15  # 6 ml/s at 0.15 m/s: 40 mm^2
    w = math.sqrt(2 * area / ASPECT)  # 8.165 mm
    s = np.arange(len(bead)) * POINT_SPACING
    inner = (s > w) & (s < s[-1] - w)  # away from the ends, where the window is whole
    assert inner.sum() > 150
    np.testing.assert_allclose(bead.widths[inner], w, rtol=1e-9)
    np.testing.assert_allclose(bead.heights[inner], ASPECT * w, rtol=1e-9)
    # Points every POINT_SPACING on the track, times where the tip was.
    # Points every POINT_SPACING on the track from its start, the last at its end; times where the tip was.
    np.testing.assert_allclose(np.diff(bead.points[:-1, 0]), POINT_SPACING, atol=1e-12)
    assert bead.points[0, 0] == 0.0 and bead.points[-1, 0] == pytest.approx(k * 0.15 * DT, abs=1e-12)
    np.testing.assert_allclose(bead.times, bead.points[:, 0] / 0.15, atol=1e-9)
    assert track.deposited == pytest.approx(6e-6 * k * DT, rel=1e-12) and track.lost == 0.0


def test_speed_step() -> None:
    speeds = [0.15] * 400 + [0.075] * 400  # at 120 mm the tip halves its speed
    track, _ = lay(STEADY, track_at(speeds), [True] * 801)
    bead = track.bead()
    a1, a2 = 6e-6 / 0.15, 6e-6 / 0.075  # 40 and 80 mm^2
    w1, w2 = math.sqrt(2 * a1 / ASPECT), math.sqrt(2 * a2 / ASPECT)
    x = bead.points[:, 0]
    step = 400 * 0.15 * DT  # where the speed changes
    before = (x > w1) & (x < step - w2)
    after = (x > step + w2) & (x < x[-1] - w2)
    np.testing.assert_allclose(bead.widths[before], w1, rtol=1e-9)
    np.testing.assert_allclose(bead.widths[after], w2, rtol=1e-9)
    # At the step the window holds half of each: A = (a1 + a2) / 2.
    at = np.argmin(np.abs(x - step))
    assert abs(x[at] - step) < 1e-9
    assert bead.widths[at] == pytest.approx(math.sqrt((a1 + a2) / ASPECT), rel=1e-9)


def test_stop_piles_a_blob() -> None:
    # 250 cycles at 0.1 m/s (50 mm), then 250 cycles (0.5 s) standing still, flow on throughout.
    speeds = [0.1] * 250 + [0.0] * 250
    track, _ = lay(STEADY, track_at(speeds), [True] * 501)
    bead = track.bead()
    a = 6e-6 / 0.1  # 60 mm^2 while moving
    blob = 6e-6 * 250 * DT  # 3 ml piled at the stop
    # At the stop the window [s - w/2, s + w/2] holds the blob and half a window of bead:
    # ASPECT w^2 / 2 * w = blob + a w / 2.
    roots = np.roots([ASPECT / 2, 0.0, -a / 2, -blob])
    w = max(r.real for r in roots if abs(r.imag) < 1e-12)
    end = np.argmax(bead.points[:, 0])
    assert bead.points[end, 0] == pytest.approx(0.05, abs=1e-12)
    assert bead.widths[end] == pytest.approx(w, rel=1e-9)
    assert 0.015 < w < 0.02  # bounded: 3 ml pile up to a 17 mm blob, not the 1 m of A = q / 0.1 mm/s
    # The bead before the blob is unaffected farther than the blob's half width.
    before = bead.points[:, 0] < 0.05 - w
    before &= bead.points[:, 0] > math.sqrt(2 * a / ASPECT)
    np.testing.assert_allclose(bead.widths[before], math.sqrt(2 * a / ASPECT), rtol=1e-9)
    # Volume is conserved: every cycle's material is on the track.
    assert track.deposited == pytest.approx(6e-6 * 500 * DT, rel=1e-12)


def test_delays_and_first_order_flow() -> None:
    p = DispenserParams(on_delay=0.05, off_delay=0.03, time_constant=0.04)
    state = FlowState()
    state, vol = flow_step(p, state, 0.0, True)  # the output is seen on at t = 0
    assert state.output and state.flow == 0.0 and vol == 0.0
    times = np.arange(1, 300) * DT
    flows, total = [], 0.0
    for t in times:
        state, vol = flow_step(p, state, t, t < 0.2)  # off from t = 0.2 s
        flows.append(state.flow)
        total += vol
    flows = np.array(flows)
    # No flow until the on delay; then 1 - exp(-(t - 0.05) / tau).
    rise = (times >= 0.05) & (times <= 0.2)
    assert np.all(flows[times < 0.05 - 1e-9] == 0.0)
    np.testing.assert_allclose(flows[rise], 1.0 - np.exp(-(times[rise] - 0.05) / 0.04), atol=1e-12)
    # Off at 0.2 s: the flow holds its value for the off delay, then falls with the same time constant.
    f_off = 1.0 - math.exp(-0.15 / 0.04)
    hold = (times > 0.2) & (times <= 0.23)
    np.testing.assert_allclose(flows[hold], 1.0 - np.exp(-(times[hold] - 0.05) / 0.04), atol=1e-12)
    fall = (times > 0.23) & (flows > 0.0)
    np.testing.assert_allclose(flows[fall], (1.0 - math.exp(-0.18 / 0.04)) * np.exp(-(times[fall] - 0.23) / 0.04),
                               atol=1e-12)
    assert f_off > 0.97
    # The volume is the exact integral: rise from 0.05 to 0.23 s, then the decay's tail until idle.
    rise_integral = 0.18 - 0.04 * (1.0 - math.exp(-0.18 / 0.04))
    peak = 1.0 - math.exp(-0.18 / 0.04)
    t_idle = times[np.flatnonzero((flows == 0.0) & (times > 0.23))[0]]  # the first idle cycle
    tail = peak * 0.04 * (1.0 - math.exp(-(t_idle - 0.23) / 0.04))
    assert total == pytest.approx(p.rate * (rise_integral + tail), rel=1e-12)
    assert state.idle and t_idle < 0.23 + 0.04 * math.log(1e3) + DT


def test_output_is_seen_in_the_cycle_it_changes() -> None:
    # With no delays and no time constant the flow follows the output in the same cycle.
    state, _ = flow_step(STEADY, FlowState(), 0.0, True)
    assert state.flow == 1.0 and state.output
    state, vol = flow_step(STEADY, state, DT, True)
    assert vol == pytest.approx(STEADY.rate * DT, rel=1e-12)
    state, _ = flow_step(STEADY, state, 2 * DT, False)
    assert state.flow == 0.0 and state.idle


def test_a_short_pulse_never_opens_the_valve() -> None:
    p = DispenserParams(on_delay=0.05, off_delay=0.01, time_constant=0.04)
    state, total = FlowState(), 0.0
    for k in range(100):
        state, vol = flow_step(p, state, k * DT, k * DT < 0.02)  # 20 ms pulse: off at 0.03 < on at 0.05
        total += vol
    assert total == 0.0 and state.idle


def test_a_run_starts_with_the_first_material() -> None:
    # Output on at t = 0 with a 50 ms delay while the tip moves at 0.1 m/s: the bead starts where the tip
    # was in the last cycle without flow, 25 cycles (50 ms) later, and no earlier.
    p = DispenserParams(on_delay=0.05, off_delay=0.0, time_constant=0.0)
    track, _ = lay(p, track_at([0.1] * 100), [True] * 101)
    bead = track.bead()
    assert bead.times[0] == pytest.approx(0.05, abs=1e-12) and bead.points[0, 0] == pytest.approx(0.005)
    assert track.deposited == pytest.approx(p.rate * (100 * DT - 0.05), rel=1e-12)


def test_no_surface_loses_the_material() -> None:
    track = BeadTrack(0.006)
    track.add(0.0, np.zeros(3), 1e-6)
    track.add(0.002, None, 2e-6)  # the nozzle points past the glass
    track.add(0.004, np.array([0.3, 0.0, 0.0]), 1e-6)  # back on a surface: a new run, not joined
    assert track.lost == 2e-6 and track.deposited == 2e-6
    bead = track.bead()
    assert len(bead) == 2 and np.allclose(bead.points[:, 0], [0.0, 0.3])
    # A spot of 1 ml laid at once is a pile as long as it is wide (wider than the nozzle):
    # ASPECT w^2 / 2 * w = 1e-6 m^3.
    w = (2 * 1e-6 / ASPECT) ** (1 / 3)
    np.testing.assert_allclose(bead.widths, w, rtol=1e-9)


@pytest.mark.parametrize('field, value, limit', [
    ('pin', 18, '0..17'), ('flow_rate', 0.0, '(0.0, 1000.0]'), ('nozzle_diameter', -1.0, '(0.0, 50.0]'),
    ('on_delay', -0.1, '[0.0, 10.0]'), ('off_delay', math.nan, '[0.0, 10.0]'), ('time_constant', 11.0, '[0.0, 10.0]'),
])
def test_bad_parameters_are_named(field: str, value: float, limit: str) -> None:
    with pytest.raises(ConfigError, match=rf"'dispenser\.{field}' = {value!r}.*{limit}".replace('(', r'\(')
                       .replace('[', r'\[').replace(']', r'\]').replace(')', r'\)')):
        DispenserParams(**{field: value})
