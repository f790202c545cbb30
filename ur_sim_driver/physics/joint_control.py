"""The robot's joint-level control of one cycle as one compiled call: the acceleration each joint can reach now,
the servo's setpoint (``servo.py``) and the computed torques (``torque_control.py``).

Built from numpy in Python this part cost about 60 us of every control cycle (limits, servo, torques, a dozen
small arrays each); compiled with numba and called once, it costs a few microseconds. The arithmetic is that of
the two modules' kernels, which their own tests cover.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import F8, FLAGS, IN1, IN2, OUT1, OUT2, VOID
from ur_sim_driver.physics.servo import JointServo, Setpoint, servo_kernel
from ur_sim_driver.physics.torque_control import PdGains, torque_kernel

# Rows of the constants array.
_V_MAX, _EFFORT_SHARE, _A_FLOOR, _A_FOLLOW, _A_BRAKE, _Q_MIN, _Q_MAX, _KP, _KD, _EFFORT_MAX = range(10)


class JointControl:
    """Servo plus computed-torque control of n joints with fixed limits.

    Args:
        servo: the setpoint generator whose state this control advances (its reset() still restarts it).
        gains: PD gains of the computed-torque law.
        v_max, effort_max, q_min, q_max: (n,) the joints' limits [rad/s], [N m], [rad].
        effort_share: (n,) torque [N m] the servo may plan accelerations with (the rest is the feedback's margin).
        a_floor, a_follow, a_brake: (n,) [rad/s^2] the least acceleration assumed reachable, the limit for
            following the reference and the one for braking at a stop point.
        dt: control period [s].
    """

    def __init__(self, servo: JointServo, gains: PdGains, v_max: np.ndarray, effort_max: np.ndarray,
                 q_min: np.ndarray, q_max: np.ndarray, effort_share: np.ndarray, a_floor: np.ndarray,
                 a_follow: np.ndarray, a_brake: np.ndarray, dt: float) -> None:
        self.servo = servo
        self.dt = float(dt)
        self.constants = np.ascontiguousarray(np.vstack(np.broadcast_arrays(
            v_max, effort_share, a_floor, a_follow, a_brake, q_min, q_max, gains.kp, gains.kd, effort_max)),
            dtype=float)
        n = self.constants.shape[1]
        self.setpoint = np.zeros((4, n))  # position, velocity, acceleration, 1.0 where limited: the last cycle's
        self.tau = np.zeros(n)
        self.saturated = np.zeros(n, dtype=np.bool_)
        self._limits = np.zeros((2, n))
        self._no_stop = np.full(n, np.nan)

    def torques(self, mass: np.ndarray, bias: np.ndarray, q: np.ndarray, qd: np.ndarray, r: np.ndarray,
                rd: np.ndarray, rdd: np.ndarray, stop: np.ndarray | None) -> np.ndarray:
        """Torques (n,) [N m] for this cycle (a new array); the servo advances and `setpoint` is this cycle's.

        Args:
            mass: (n, n) M(q) [kg m^2]; bias: (n,) h(q, qd) [N m].
            q, qd: (n,) measured state [rad], [rad/s].
            r, rd, rdd: (n,) reference [rad], [rad/s], [rad/s^2] in real time.
            stop: (n,) positions the setpoint must not pass [rad], or None.
        """
        control_kernel(mass, bias, q, qd, r, rd, rdd, self._no_stop if stop is None else stop, self.servo.state,
                       self.constants, self.dt, self.servo.gain, self._limits, self.setpoint, self.tau,
                       self.saturated)
        return self.tau.copy()

    def last_setpoint(self) -> Setpoint:
        """The setpoint of the last cycle, as copies."""
        sp = self.setpoint
        return Setpoint(sp[0].copy(), sp[1].copy(), sp[2].copy(), sp[3] != 0.0)


@njit(VOID(IN2, IN1, IN1, IN1, IN1, IN1, IN1, IN1, OUT2, IN2, F8, F8, OUT2, OUT2, OUT1, FLAGS), cache=True)
def control_kernel(mass, bias, q, qd, r, rd, rdd, stop, servo_state, c, dt, gain, limits, setpoint, tau, saturated):
    """One cycle of JointControl.torques: writes limits (2, n), setpoint (4, n), tau (n,), saturated (n,)."""
    for i in range(q.shape[0]):
        # What the joint can accelerate at now: the type's limit, or less where the effort limit (after gravity
        # and Coriolis torques) allows less. The diagonal of M is the joint's own inertia.
        reachable = max((c[_EFFORT_SHARE, i] - abs(bias[i])) / mass[i, i], c[_A_FLOOR, i])
        limits[0, i] = min(reachable, c[_A_FOLLOW, i])
        limits[1, i] = min(reachable, c[_A_BRAKE, i])
    servo_kernel(r, rd, rdd, servo_state, c[_V_MAX], limits[0], limits[1], c[_Q_MIN], c[_Q_MAX], stop, dt, gain,
                 setpoint)
    torque_kernel(mass, bias, q, qd, setpoint[0], setpoint[1], setpoint[2], c[_KP], c[_KD], c[_EFFORT_MAX],
                  c[_V_MAX], dt, True, tau, saturated)
