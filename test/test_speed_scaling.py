"""The robot's own speed scaling: velocity and lag fractions, reaction rates, the ramped input."""
import numpy as np
import pytest

from ur_sim_driver.speed_scaling import (
    FALL_TIME,
    LAG_DEAD_ZONE,
    LAG_SPAN,
    RISE_TIME,
    VELOCITY_MARGIN,
    RobotSpeedScaling,
    lag_fraction,
    velocity_fraction,
)

V_MAX = np.array([3.0, 2.0])
A_MAX = np.array([5.0, 5.0])


def test_velocity_fraction_keeps_the_scaled_reference_under_the_limit():
    assert velocity_fraction(np.array([1.0, 1.0]), V_MAX, 1.0) == 1.0
    f = velocity_fraction(np.array([1.0, 20.0]), V_MAX, 1.0)
    assert f == pytest.approx(VELOCITY_MARGIN * 2.0 / 20.0)
    # The user's input factor already slows the reference: less robot slowdown is needed.
    assert velocity_fraction(np.array([1.0, 20.0]), V_MAX, 0.5) == pytest.approx(2 * f)
    assert velocity_fraction(np.zeros(2), V_MAX, 1.0) == 1.0


def test_lag_fraction_falls_from_the_dead_zone_to_zero():
    assert lag_fraction(np.array([0.0, LAG_DEAD_ZONE])) == 1.0
    assert lag_fraction(np.array([LAG_DEAD_ZONE + LAG_SPAN / 2, 0.0])) == pytest.approx(0.5)
    assert lag_fraction(np.array([-(LAG_DEAD_ZONE + LAG_SPAN), 0.0])) == 0.0


def test_factor_falls_and_rises_at_limited_rates():
    s = RobotSpeedScaling(V_MAX, A_MAX)
    dt = 0.002
    s.update(np.array([0.0, 200.0]), np.zeros(2), 1.0, dt)  # wants ~0.01 at once
    assert s.factor == pytest.approx(1.0 - dt / FALL_TIME)
    for _ in range(1000):
        s.update(np.array([0.0, 200.0]), np.zeros(2), 1.0, dt)
    assert s.factor == pytest.approx(VELOCITY_MARGIN * 2.0 / 200.0)
    before = s.factor
    s.update(np.zeros(2), np.zeros(2), 1.0, dt)
    assert s.factor == pytest.approx(before + dt / RISE_TIME)


def test_lower_input_is_ramped_at_the_acceleration_limit_and_a_higher_one_applied_at_once():
    s = RobotSpeedScaling(V_MAX, A_MAX)
    dt = 0.002
    rate = np.array([2.0, 0.0])  # reference moves joint 0 at 2 rad/s at factor 1
    s.update(rate, np.zeros(2), 0.0, dt)  # pause
    assert s.input == pytest.approx(1.0 - 5.0 / 2.0 * dt)  # velocity falls by a_max * dt
    for _ in range(1000):
        s.update(rate, np.zeros(2), 0.0, dt)
    assert s.input == 0.0 and s.total == 0.0
    s.update(rate, np.zeros(2), 0.7, dt)
    assert s.input == 0.7
    # While holding (no motion), a pause applies at once.
    held = RobotSpeedScaling(V_MAX, A_MAX)
    held.update(np.zeros(2), np.zeros(2), 0.0, dt)
    assert held.input == 0.0
