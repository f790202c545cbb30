"""The robot's own speed scaling: velocity and lag fractions, reaction rates, the slider; and which factor each
trajectory controller advances by (the scaled one the robot's, the plain one its own)."""
import numpy as np
import pytest

from ur_sim_driver.robot.speed_scaling import (
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
    assert velocity_fraction(np.array([1.0, 1.0]), V_MAX) == 1.0
    f = velocity_fraction(np.array([1.0, 20.0]), V_MAX)
    assert f == pytest.approx(VELOCITY_MARGIN * 2.0 / 20.0)
    # The slider already slows the reference: less robot slowdown is needed.
    assert velocity_fraction(np.array([1.0, 20.0]), V_MAX, 0.5) == pytest.approx(2 * f)
    assert velocity_fraction(np.zeros(2), V_MAX) == 1.0


def test_lag_fraction_falls_from_the_dead_zone_to_zero():
    assert lag_fraction(np.array([0.0, LAG_DEAD_ZONE])) == 1.0
    assert lag_fraction(np.array([LAG_DEAD_ZONE + LAG_SPAN / 2, 0.0])) == pytest.approx(0.5)
    assert lag_fraction(np.array([-(LAG_DEAD_ZONE + LAG_SPAN), 0.0])) == 0.0


def test_factor_falls_and_rises_at_limited_rates():
    s = RobotSpeedScaling(V_MAX, A_MAX)
    dt = 0.002
    s.update(np.array([0.0, 200.0]), np.zeros(2), dt)  # wants ~0.01 at once
    assert s.factor == pytest.approx(1.0 - dt / FALL_TIME)
    for _ in range(1000):
        s.update(np.array([0.0, 200.0]), np.zeros(2), dt)
    assert s.factor == pytest.approx(VELOCITY_MARGIN * 2.0 / 200.0)
    before = s.factor
    s.update(np.zeros(2), np.zeros(2), dt)
    assert s.factor == pytest.approx(before + dt / RISE_TIME)


def test_slider_applies_at_once_while_holding_and_multiplies_the_reported_factor():
    s = RobotSpeedScaling(V_MAX, A_MAX)
    s.slider = 0.3
    s.update(np.zeros(2), np.zeros(2), 0.002)
    assert s.slider_applied == 0.3 and s.factor == pytest.approx(0.3)


def test_slider_is_ramped_at_the_acceleration_limit_while_moving():
    s = RobotSpeedScaling(V_MAX, A_MAX)
    dt = 0.002
    rate = np.array([2.0, 0.0])  # joint 0 at 2 rad/s at factor 1
    s.slider = 0.1
    s.update(rate, np.zeros(2), dt)
    assert s.slider_applied == pytest.approx(1.0 - 5.0 / 2.0 * dt)  # velocity falls by a_max * dt
    velocities = []
    for _ in range(1000):
        s.update(rate, np.zeros(2), dt)
        velocities.append(rate[0] * s.factor)
    assert s.slider_applied == pytest.approx(0.1) and s.factor == pytest.approx(0.1)
    assert np.abs(np.diff(velocities)).max() <= 5.0 * dt * (1 + 1e-9)
    # Back up: ramped the same way, not at once.
    s.slider = 1.0
    s.update(rate, np.zeros(2), dt)
    assert s.slider_applied == pytest.approx(0.1 + 5.0 / 2.0 * dt)


def test_slider_spares_the_robots_own_slowdown():
    # A reference at 1.5x joint 1's limit: at slider 1 the robot slows itself, at slider 0.5 it need not.
    rate = np.array([0.0, 3.0])
    fast, slow = RobotSpeedScaling(V_MAX, A_MAX), RobotSpeedScaling(V_MAX, A_MAX)
    slow.slider = 0.5
    slow.update(np.zeros(2), np.zeros(2), 0.002)  # applied while holding
    for _ in range(500):
        fast.update(rate, np.zeros(2), 0.002)
        slow.update(rate, np.zeros(2), 0.002)
    assert fast.own == pytest.approx(VELOCITY_MARGIN * 2.0 / 3.0) and fast.factor == fast.own
    assert slow.own == 1.0 and slow.factor == pytest.approx(0.5)
    assert abs(rate[1]) * slow.factor <= VELOCITY_MARGIN * V_MAX[1]


def test_trajectory_time_follows_the_slider():
    from ur_sim_driver.motion.jtc import TrajectoryController
    from ur_sim_driver.motion.tolerances import default_tolerances
    from ur_sim_driver.motion.trajectory_types import TrajectoryPoints

    names = ('a', 'b')
    tol = default_tolerances(names, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=0.0)
    jtc = TrajectoryController(names, tol, np.zeros(2), V_MAX, A_MAX)
    jtc.scaling.slider = 0.25
    dt = 0.002
    q = np.zeros(2)
    jtc.update(0.0, dt, q, q)  # holding: the slider applies at once
    points = TrajectoryPoints(names, np.array([4.0]), np.array([[0.4, 0.0]]), np.zeros((1, 2)), np.zeros((1, 2)),
                              np.array([False]), np.array([False]))
    jtc.start(points, dt, q, q)
    for k in range(1, 501):
        sample, _ = jtc.update(k * dt, dt, q, np.zeros(2))
        q = sample.positions  # a perfect arm
    # 1 s of real time is 0.25 s of trajectory time (the slow reference needs no slowdown of the robot's own).
    assert jtc.trajectory_time - dt == pytest.approx(500 * dt * 0.25)
    assert jtc.scaling.factor == pytest.approx(0.25)


def test_update_at_rest_equals_update_with_a_reference_at_rest():
    rng = np.random.default_rng(7)
    zero = np.zeros(2)
    for _ in range(200):
        a, b = RobotSpeedScaling(V_MAX, A_MAX), RobotSpeedScaling(V_MAX, A_MAX)
        a.slider = b.slider = float(rng.uniform(0.0, 1.0))
        # the same random history on both: moving cycles that slow the robot and ramp the slider
        for _ in range(5):
            rate, lag = rng.uniform(-6, 6, 2), rng.uniform(-0.2, 0.2, 2)
            a.update(rate, lag, 0.002)
            b.update(rate, lag, 0.002)
        assert a.own < 1.0 or a.slider_applied != a.slider  # something for the rest to settle
        for _ in range(30):
            assert a.update(zero, zero, 0.002) == b.update_at_rest(0.002)
            assert (a.slider_applied, a.own) == (b.slider_applied, b.own)


def _controller(scaled: bool, own: float):
    from ur_sim_driver.motion.jtc import TrajectoryController
    from ur_sim_driver.motion.tolerances import default_tolerances
    from ur_sim_driver.motion.trajectory_types import TrajectoryPoints

    names = ('a', 'b')
    tol = default_tolerances(names, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=0.0)
    jtc = TrajectoryController(names, tol, np.zeros(2), V_MAX, A_MAX, speed_scaling=own, scaled=scaled)
    jtc.scaling.slider = 0.5
    jtc.update(0.0, 0.002, np.zeros(2), np.zeros(2))  # holding: the slider applies at once
    points = TrajectoryPoints(names, np.array([10.0]), np.array([[0.4, 0.0]]), np.zeros((1, 2)), np.zeros((1, 2)),
                              np.array([False]), np.array([False]))
    jtc.start(points, 0.002, np.zeros(2), np.zeros(2))
    return jtc


@pytest.mark.parametrize(('scaled', 'own', 'rate'), [
    (True, 1.0, 0.5), (True, 0.0, 0.5), (True, 3.0, 0.5),  # the robot's factor (slider 0.5), whatever its own
    (False, 1.0, 1.0), (False, 0.0, 0.0), (False, 2.5, 2.5),  # its own factor (0 pauses, above 1 speeds up)
])
def test_each_controller_advances_by_its_factor(scaled, own, rate):
    """Upstream: the scaled controller advances trajectory time by the hardware's speed_scaling_factor; the plain
    one by its own (initial_scaling_factor, then speed_scaling_input), whatever the slider."""
    jtc = _controller(scaled, own)
    q = np.zeros(2)
    dt = 0.002
    for k in range(1, 101):
        sample, _ = jtc.update(k * dt, dt, q, np.zeros(2))
        q = sample.positions  # a perfect arm
    assert jtc.trajectory_time - 0.002 == pytest.approx(100 * dt * rate)
    assert jtc.speed_scaling == own  # what its controller_state reports, in the scaled one too
