"""Computed-torque control: the model-based law, effort clipping and the drives' torque-speed curve."""
import numpy as np

from ur_sim_driver.physics.torque_control import PdGains, computed_torque, drive_torque_bounds

RNG = np.random.default_rng(7)
N = 6
GAINS = PdGains.critically_damped(N, 500.0)
EFFORT = np.full(N, 150.0)
V_MAX = np.full(N, 3.0)


def _spd(n=N):
    a = RNG.normal(size=(n, n))
    return a @ a.T + n * np.eye(n)


def test_gains_are_critically_damped_at_three_tenths_of_the_rate():
    g = PdGains.critically_damped(2, 500.0)
    assert np.allclose(g.kp, 150.0**2) and np.allclose(g.kd, 300.0)


def test_unsaturated_torque_is_the_model_times_the_pd_acceleration_plus_bias():
    m, bias = _spd() * 0.1, RNG.normal(size=N)
    q, qd = RNG.normal(size=N) * 0.01, RNG.normal(size=N) * 0.01
    q_ref, qd_ref, qdd_ref = q + 1e-4, qd + 1e-3, RNG.normal(size=N) * 0.1
    tau, saturated = computed_torque(m, bias, q, qd, q_ref, qd_ref, qdd_ref, GAINS, EFFORT)
    accel = qdd_ref + GAINS.kp * (q_ref - q) + GAINS.kd * (qd_ref - qd)
    assert np.allclose(tau, m @ accel + bias, rtol=0, atol=1e-9)
    assert not saturated.any()


def test_torque_is_clipped_to_the_effort_limit_and_flagged():
    m, bias = np.eye(N), np.zeros(N)
    q_ref = np.zeros(N)
    q_ref[0], q_ref[1] = 1.0, -1.0  # 22500 rad/s^2 on an inertia of 1: far beyond 150 N m
    tau, saturated = computed_torque(m, bias, np.zeros(N), np.zeros(N), q_ref, np.zeros(N), np.zeros(N), GAINS, EFFORT)
    assert tau[0] == 150.0 and tau[1] == -150.0
    assert saturated.tolist() == [True, True, False, False, False, False]


def test_acceleration_is_limited_so_that_the_next_velocity_stays_within_the_limit():
    m, bias, dt = np.eye(N), np.zeros(N), 0.002
    qd = np.full(N, 2.99)
    tau, _ = computed_torque(m, bias, np.zeros(N), qd, np.full(N, 1.0), np.zeros(N), np.zeros(N), GAINS,
                             np.full(N, 1e6), V_MAX, dt)
    # accel = tau / 1: qd + accel dt must not pass 3 rad/s (and the drive's curve gives at most that).
    assert np.all(qd + tau * dt <= V_MAX + 1e-12)


def test_drive_pushes_nothing_at_its_speed_limit_and_brakes_fully():
    lo, hi = drive_torque_bounds(3.0, 3.0, 150.0)
    assert hi == 0.0 and lo == -150.0
    lo, hi = drive_torque_bounds(0.0, 3.0, 150.0)
    assert (lo, hi) == (-150.0, 150.0)
    lo, hi = drive_torque_bounds(2.985, 3.0, 150.0)  # half way through the 1 % knee
    assert np.isclose(hi, 75.0) and lo == -150.0
    lo, hi = drive_torque_bounds(-3.1, 3.0, 150.0)  # beyond the limit backwards: the drive pushes it back
    assert lo == 150.0 and hi == 150.0


def test_speed_curve_bounds_the_torque_at_speed():
    m, bias = np.eye(N), np.zeros(N)
    qd = np.full(N, 3.0)
    tau, saturated = computed_torque(m, bias, np.zeros(N), qd, np.full(N, 1.0), qd, np.zeros(N), GAINS, EFFORT,
                                     V_MAX, 0.0)
    assert np.all(tau <= 0.0) and saturated.all()
