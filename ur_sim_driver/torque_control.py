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
Efforts are clipped to the type's limits before they reach the actuators.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# omega * control_period: see the module docstring.
_OMEGA_TIMES_PERIOD = 0.3


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
) -> tuple[np.ndarray, np.ndarray]:
    """Joint torques that make the arm follow the reference.

    Args:
        mass_matrix: (n, n) joint-space inertia M(q) [kg m^2], including rotor armature.
        bias: (n,) gravity + Coriolis - passive torques h(q, qd) [N m].
        q, qd: (n,) measured position [rad] and velocity [rad/s].
        q_ref, qd_ref, qdd_ref: (n,) reference [rad], [rad/s], [rad/s^2].
        gains: PD gains.
        effort_max: (n,) torque limits [N m].

    Returns:
        (tau, saturated): tau (n,) clipped to +-effort_max [N m]; saturated (n,) bool where clipping acted.
    """
    accel = qdd_ref + gains.kp * (q_ref - q) + gains.kd * (qd_ref - qd)
    tau = mass_matrix @ accel + bias
    clipped = np.clip(tau, -effort_max, effort_max)
    return clipped, clipped != tau
