"""The controller's scaled clock and the switch events handed out on it (pure)."""
import pytest

from ur_glue_planner.execution.switch_timer import ScaledClock, SwitchEvent, SwitchSequence


def test_clock_runs_unscaled_before_the_start_and_scaled_after():
    clock = ScaledClock(start=10.0)
    assert clock.update(9.5, 1.0) == pytest.approx(-0.5)
    assert clock.update(10.2, 1.0) == pytest.approx(0.2)
    assert clock.update(10.4, 0.5) == pytest.approx(0.3)  # 0.2 s at half speed
    assert clock.update(10.4, 0.5) == pytest.approx(0.3)  # the same stamp twice advances nothing
    assert clock.update(11.4, 0.0) == pytest.approx(0.3)  # paused (speed slider at 0, protective stop)
    assert clock.time == pytest.approx(0.3) and clock.now == pytest.approx(0.3)
    assert ScaledClock(start=1.0).update(0.9, 1.0) == pytest.approx(-0.1)
    assert clock.update(11.6, 2.0) == pytest.approx(0.7)  # the plain JTC's own factor may exceed 1


def test_events_are_due_once_in_time_order_half_a_period_early():
    seq = SwitchSequence([SwitchEvent(2.0, 16, False, 'off'), SwitchEvent(0.5, 16, True, 'on')], half_period=0.001)
    assert seq.due(0.4) == []
    assert [e.what for e in seq.due(0.4995)] == ['on']
    assert seq.due(1.0) == []
    assert [e.what for e in seq.due(5.0)] == ['off']
    assert seq.due(6.0) == [] and seq.pending == []
