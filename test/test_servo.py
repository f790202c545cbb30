"""The robot's setpoint generator: exact on feasible references, within limits and never ahead otherwise."""
import numpy as np

from ur_sim_driver.physics.servo import JointServo, ServoLimits, approach_velocity

N = 2
DT = 0.002
LIMITS = ServoLimits(v_max=np.full(N, 3.0), a_max=np.full(N, 5.0), a_stop=np.full(N, 10.0),
                     q_min=np.full(N, -6.0), q_max=np.full(N, 6.0))


def run(reference, steps, stop=None, limits=LIMITS, q0=0.0):
    """Drive a servo with reference(t) -> (r, rd, rdd); return times, setpoint positions/velocities/accelerations."""
    servo = JointServo(np.full(N, q0), 1.0 / DT)
    out = []
    for k in range(steps):
        r, rd, rdd = reference(k * DT)
        sp = servo.step(np.full(N, r), np.full(N, rd), np.full(N, rdd), DT, limits, stop)
        out.append((k * DT, sp.positions[0], sp.velocities[0], sp.accelerations[0], r, sp.limited[0]))
    return np.array(out).T


def test_feasible_reference_passes_through_exactly():
    def quintic(t):  # 0 -> 0.5 rad in 1 s, rest to rest: peak 0.94 rad/s, 2.9 rad/s^2
        s = min(t, 1.0)
        return (0.5 * (10 * s**3 - 15 * s**4 + 6 * s**5), 0.5 * (30 * s**2 - 60 * s**3 + 30 * s**4),
                0.5 * (60 * s - 180 * s**2 + 120 * s**3))
    t, p, v, a, r, limited = run(quintic, 600)
    assert np.abs(p - r).max() < 1e-9
    assert not limited.any()


def test_velocity_step_is_followed_within_limits_and_from_behind():
    # A reference that jumps to 2 rad/s at t = 0 (a linear segment): infeasible in acceleration.
    t, p, v, a, r, limited = run(lambda t: (2.0 * t, 2.0, 0.0), 1000)
    assert np.abs(v).max() <= 3.0 + 1e-12
    assert np.abs(a).max() <= 5.0 + 1e-9
    assert (p <= r + 1e-6).all()  # never ahead of the reference
    assert limited[0] and not limited[-1]  # it catches up and then passes the reference through
    assert abs(p[-1] - r[-1]) < 1e-6


def test_too_fast_reference_is_followed_at_the_velocity_limit():
    t, p, v, a, r, _ = run(lambda t: (10.0 * t, 10.0, 0.0), 1000)
    assert np.abs(v).max() <= 3.0 + 1e-12
    assert abs(v[-1] - 3.0) < 1e-9


def test_abrupt_stop_is_not_overshot_at_the_stop_point():
    # Reference at 2 rad/s stopping dead at 1 rad; the servo brakes at a_stop so that it ends on the point.
    def ramp(t):
        return (min(2.0 * t, 1.0), 2.0 if t < 0.5 else 0.0, 0.0)
    t, p, v, a, r, _ = run(ramp, 1500, stop=np.full(N, 1.0))
    assert p.max() <= 1.0 + 1e-5  # [rad]: 0.01 mrad, the period's discreteness
    assert abs(p[-1] - 1.0) < 1e-5
    assert np.abs(a).max() <= 10.0 * 1.01


def test_without_a_stop_point_an_abrupt_stop_is_overshot():
    # The same reference with no stop point given: the servo cannot know and passes 1 rad (shows the guard acts).
    def ramp(t):
        return (min(2.0 * t, 1.0), 2.0 if t < 0.5 else 0.0, 0.0)
    _, p, _, _, _, _ = run(ramp, 1500)
    assert p.max() > 1.01


def test_position_limits_are_never_passed():
    limits = ServoLimits(LIMITS.v_max, LIMITS.a_max, LIMITS.a_stop, np.full(N, -1.0), np.full(N, 1.0))
    t, p, v, a, r, _ = run(lambda t: (3.0 * t, 3.0, 0.0), 2000, limits=limits)
    assert p.max() <= 1.0 + 1e-5
    assert abs(p[-1] - 1.0) < 1e-5


def test_approach_velocity_is_linear_near_zero_and_sqrt_far():
    a = np.array([5.0])
    assert np.isclose(approach_velocity(np.array([1e-4]), 100.0, a)[0], 1e-2)
    # Far away: sqrt(2 a' d) with a' half the limit (the other half absorbs the period's discreteness).
    assert np.isclose(approach_velocity(np.array([-1.0]), 100.0, a)[0], -np.sqrt(5.0))
