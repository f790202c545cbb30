"""The compiled control cycle equals its parts: reachable accelerations, the servo's step and computed torque."""
import numpy as np

from ur_sim_driver.physics.joint_control import JointControl
from ur_sim_driver.physics.servo import JointServo, ServoLimits
from ur_sim_driver.physics.torque_control import PdGains, computed_torque

N, RATE, DT = 6, 500.0, 0.002
RNG = np.random.default_rng(3)
V_MAX, EFFORT = np.full(N, 3.14), np.array([150.0, 150.0, 150.0, 28.0, 28.0, 28.0])
Q_MIN, Q_MAX = np.full(N, -6.28), np.full(N, 6.28)
A_MAX = np.full(N, 5.0)


def _control(q0):
    return JointControl(JointServo(q0, RATE), PdGains.critically_damped(N, RATE), V_MAX, EFFORT, Q_MIN, Q_MAX,
                        effort_share=0.9 * EFFORT, a_floor=0.05 * A_MAX, a_follow=1.05 * A_MAX,
                        a_brake=2.0 * A_MAX, dt=DT)


def _by_parts(servo, mass, bias, q, qd, r, rd, rdd, stop):
    reachable = np.maximum((0.9 * EFFORT - np.abs(bias)) / mass.diagonal(), 0.05 * A_MAX)
    limits = ServoLimits(V_MAX, np.minimum(reachable, 1.05 * A_MAX), np.minimum(reachable, 2.0 * A_MAX), Q_MIN, Q_MAX)
    sp = servo.step(r, rd, rdd, DT, limits, stop)
    tau, _ = computed_torque(mass, bias, q, qd, sp.positions, sp.velocities, sp.accelerations,
                             PdGains.critically_damped(N, RATE), EFFORT, V_MAX, DT)
    return sp, tau


def test_one_call_equals_the_parts_over_random_cycles():
    q0 = RNG.uniform(-1, 1, N)
    control, servo = _control(q0), JointServo(q0, RATE)
    limited_seen = 0
    for k in range(300):
        a = RNG.normal(size=(N, N))
        mass = 0.05 * a @ a.T + 0.5 * np.eye(N)
        bias = RNG.normal(size=N) * 40.0
        q, qd = q0 + RNG.normal(size=N) * 0.01, RNG.normal(size=N) * 0.5
        r, rd, rdd = q0 + RNG.normal(size=N) * 0.2, RNG.normal(size=N) * 3.0, RNG.normal(size=N) * 8.0
        stop = None if k % 2 else q0 + RNG.normal(size=N) * 0.3
        if k % 3 == 0:  # a trajectory's arrays are frozen (read-only): accepted as they are
            for a in (r, rd, rdd) + (() if stop is None else (stop,)):
                a.flags.writeable = False
        tau = control.torques(mass, bias, q, qd, r, rd, rdd, stop)
        sp, tau_parts = _by_parts(servo, mass, bias, q, qd, r, rd, rdd, stop)
        fused = control.last_setpoint()
        assert np.allclose(tau, tau_parts, rtol=0, atol=1e-9)
        for got, want in ((fused.positions, sp.positions), (fused.velocities, sp.velocities),
                          (fused.accelerations, sp.accelerations)):
            assert np.array_equal(got, want)
        assert np.array_equal(fused.limited, sp.limited)
        limited_seen += int(sp.limited.any())
    assert limited_seen > 100  # the random references bind the limits in most cycles: those paths ran too


def test_torques_returns_a_new_array_and_the_servo_state_advances():
    q0 = np.zeros(N)
    control = _control(q0)
    mass, bias = np.eye(N), np.zeros(N)
    tau1 = control.torques(mass, bias, q0, q0, q0 + 0.1, q0, q0, None)
    tau2 = control.torques(mass, bias, q0, q0, q0 + 0.1, q0, q0, None)
    assert tau1 is not tau2 and not np.shares_memory(tau1, control.tau)
    assert np.all(control.servo.state[1] > 0.0)  # accelerating towards the reference, within its limits
    assert np.all(np.abs(control.servo.state[1]) <= V_MAX)
