"""Joint-space computed-torque control with PD feedback, as the simulated arm's low-level controller.

The real UR controller tracks the JTC reference with its own (unpublished) servo loop; here a model-based
controller stands in for it: ``tau = M(q) (qdd_ref + Kp e + Kd e_dot) + h(q, qd)``, where ``h`` is
gravity, Coriolis and the model's passive (damping) torques. With an exact model the closed-loop error
obeys ``e_ddot + Kd e_dot + Kp e = 0``, so the gains set the error dynamics directly.

Gains (per joint, the same for all joints): natural frequency ``omega`` and damping ratio 1 give
``Kp = omega^2`` and ``Kd = 2 omega``. ``omega`` is a fixed fraction (0.3) of the control rate, so that the
zero-order-hold loop stays well inside its stability region (Kd T = 0.6, Kp T^2 = 0.09): 500 Hz ->
omega = 150 rad/s (Kp 22500, Kd 300); 125 Hz -> 37.5 rad/s (Kp 1406, Kd 75). Measured on the benchmark's
6-joint trajectory, the tracking error stays below 0.05 mrad at 500 Hz and 0.4 mrad at 125 Hz
(out/bench/sim.json); a fraction of 0.1 gave 0.07 and 1.0 mrad.
Efforts are clipped to the type's limits before they reach the actuators. The commanded acceleration never
asks a joint to exceed its velocity limit within the next period, and the drive's torque in the direction of
motion falls to zero as the joint reaches its velocity limit (a motor's torque-speed curve, from the back-EMF of
its windings): no coupling torque from another joint can then push it faster, while braking torque stays at
full strength. Whatever the reference, the measured joint speed stays at its limit.
The per-cycle arithmetic is compiled with numba (``torque_kernel``): in numpy it cost about 30 us a cycle.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit, types

from ur_sim_driver.physics.numba_types import B1, F8, FLAGS, IN1, IN2, OUT1, VOID

# omega * control_period: see the module docstring.
_OMEGA_TIMES_PERIOD = 0.3
# Speed, as a share of the limit, above which the driving torque falls linearly to zero at the limit.
SPEED_KNEE = 0.99


@dataclass(frozen=True, eq=False)
class PdGains:
    """Acceleration-level PD gains.

    Attributes:
        kp: (n,) [1/s^2].
        kd: (n,) [1/s].
    """

    kp: np.ndarray
    kd: np.ndarray

    @classmethod
    def critically_damped(cls, n: int, control_rate: float) -> PdGains:
        """Gains with natural frequency 0.3 x control rate [rad/s] and damping ratio 1."""
        omega = _OMEGA_TIMES_PERIOD * control_rate
        return cls(kp=np.full(n, omega**2), kd=np.full(n, 2.0 * omega))


def computed_torque(
    mass_matrix: np.ndarray,
    bias: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    q_ref: np.ndarray,
    qd_ref: np.ndarray,
    qdd_ref: np.ndarray,
    gains: PdGains,
    effort_max: np.ndarray,
    v_max: np.ndarray | None = None,
    dt: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Joint torques that make the arm follow the reference.

    Args:
        mass_matrix: (n, n) joint-space inertia M(q) [kg m^2], including rotor armature.
        bias: (n,) gravity + Coriolis - passive torques h(q, qd) [N m].
        q, qd: (n,) measured position [rad] and velocity [rad/s].
        q_ref, qd_ref, qdd_ref: (n,) reference [rad], [rad/s], [rad/s^2].
        gains: PD gains.
        effort_max: (n,) torque limits [N m].
        v_max: (n,) velocity limits [rad/s]; with `dt` > 0 the acceleration is limited so that
            |qd + accel dt| <= v_max.
        dt: control period [s].

    Returns:
        (tau, saturated): tau (n,) clipped to +-effort_max [N m]; saturated (n,) bool where clipping acted.
    """
    n = len(q)
    tau, saturated = np.empty(n), np.zeros(n, dtype=np.bool_)
    limit_speed = v_max is not None
    torque_kernel(np.asarray(mass_matrix, dtype=float), np.asarray(bias, dtype=float), np.asarray(q, dtype=float),
                  np.asarray(qd, dtype=float), np.asarray(q_ref, dtype=float), np.asarray(qd_ref, dtype=float),
                  np.asarray(qdd_ref, dtype=float), gains.kp, gains.kd, np.asarray(effort_max, dtype=float),
                  np.asarray(v_max, dtype=float) if limit_speed else np.full(n, np.inf), dt if limit_speed else 0.0,
                  limit_speed, tau, saturated)
    return tau, saturated


@njit(types.UniTuple(F8, 2)(F8, F8, F8), cache=True)
def drive_torque_bounds(qd: float, v_max: float, effort_max: float) -> tuple[float, float]:
    """Torque bounds (lo, hi) [N m] of a drive at speed qd [rad/s]: full effort, except that the torque pushing the
    joint in its direction of motion falls linearly from SPEED_KNEE x v_max to 0 at v_max (and brakes beyond)."""
    band = (1.0 - SPEED_KNEE) * v_max
    hi = effort_max * min(max((v_max - qd) / band, -1.0), 1.0)
    lo = -effort_max * min(max((v_max + qd) / band, -1.0), 1.0)
    return lo, hi


@njit(VOID(IN2, IN1, IN1, IN1, IN1, IN1, IN1, IN1, IN1, IN1, IN1, F8, B1, OUT1, FLAGS), cache=True)
def torque_kernel(mass_matrix, bias, q, qd, q_ref, qd_ref, qdd_ref, kp, kd, effort_max, v_max, dt, speed_curve,
                  tau, saturated):
    """computed_torque, compiled (it runs every control cycle): writes tau (n,) [N m] and saturated (n,).

    `dt` > 0 limits the acceleration to |qd + accel dt| <= v_max; `speed_curve` applies the drives' torque-speed
    curve (drive_torque_bounds) instead of the plain +-effort_max.
    """
    n = q.shape[0]
    accel = np.empty(n)
    for i in range(n):
        a = qdd_ref[i] + kp[i] * (q_ref[i] - q[i]) + kd[i] * (qd_ref[i] - qd[i])
        if dt > 0.0:
            a = min(max(a, (-v_max[i] - qd[i]) / dt), (v_max[i] - qd[i]) / dt)
        accel[i] = a
    for i in range(n):
        t = bias[i]
        for j in range(n):
            t += mass_matrix[i, j] * accel[j]
        if speed_curve:
            lo, hi = drive_torque_bounds(qd[i], v_max[i], effort_max[i])
        else:
            lo, hi = -effort_max[i], effort_max[i]
        clipped = min(max(t, lo), hi)
        tau[i] = clipped
        saturated[i] = clipped != t
