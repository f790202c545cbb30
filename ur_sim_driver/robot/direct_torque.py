"""The robot's torque control (URScript ``direct_torque``, the driver's effort command interface), without ROS.

Facts (the UR driver at a16a268 and its client library's External Control script, the URScript manual of 5.25.1):

* The commanded torques come *on top of* the robot's gravity compensation, which uses the gravity vector the
  controller believes in (``set_gravity``, the gravity_update_controller) and the payload it believes is mounted
  (``set_payload``): with the right beliefs a zero command holds the arm still; a wrong belief makes it drift.
  Coriolis and centrifugal torques are not compensated.
* The robot compensates part of its joints' friction, scaled per joint in [0, 1]: viscous and Coulomb scales,
  by default viscous 0.9 (0.8 for the elbow) and Coulomb 0.8 (0.7 for the elbow); 0 means no compensation, 1 full.
  The scales are set through the friction_model_controller (robot software 5.25.1 / 10.12.1 or later).
* The torques are not scaled by the speed slider; the user is responsible for commands the robot can follow, and
  the robot's safety limits still stop it.
* Torque control switched off, the script ends its torque thread with ``stopj(4.0)``: the arm brakes and holds.

ur_sim's joints carry viscous friction (``simulation.damping``) and Coulomb friction (``simulation.coulomb``),
both estimates per robot type. Under position, velocity and passthrough control the robot's servo cancels the
Coulomb friction entirely (the simulated arm does not carry it then); under torque control the arm feels what
the compensation leaves: ``(1 - scale) x friction`` (:func:`felt_friction`). The safety system, which in the
other modes watches a reference, watches the measured motion here (:func:`motion_limit_cause`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The External Control script ends its torque thread (torque control switched off) with stopj(4.0).
STOPJ_DECELERATION = 4.0  # [rad/s^2]
DEFAULT_VISCOUS_SCALE = (0.9, 0.9, 0.8, 0.9, 0.9, 0.9)
DEFAULT_COULOMB_SCALE = (0.8, 0.8, 0.7, 0.8, 0.8, 0.8)


@dataclass(frozen=True, eq=False)
class FrictionScales:
    """How much of each joint's friction the robot compensates under torque control, each in [0, 1].

    Attributes:
        viscous: (6,) scales of the viscous friction compensation.
        coulomb: (6,) scales of the Coulomb friction compensation.
    """

    viscous: np.ndarray
    coulomb: np.ndarray

    @staticmethod
    def make(viscous, coulomb) -> FrictionScales:
        """Scales clamped to [0, 1], as the client library clamps them before they reach the robot."""
        v, c = (np.clip(np.asarray(x, dtype=float), 0.0, 1.0) for x in (viscous, coulomb))
        v.flags.writeable = c.flags.writeable = False
        return FrictionScales(v, c)


DEFAULT_SCALES = FrictionScales.make(DEFAULT_VISCOUS_SCALE, DEFAULT_COULOMB_SCALE)


def felt_friction(damping: np.ndarray, coulomb: np.ndarray, scales: FrictionScales) -> tuple[np.ndarray, np.ndarray]:
    """The friction the joints feel under torque control: viscous (n,) [N m s/rad] and Coulomb (n,) [N m], what
    the robot's compensation leaves of the joints' `damping` and `coulomb`."""
    return (1.0 - scales.viscous) * damping, (1.0 - scales.coulomb) * coulomb


def motion_limit_cause(q: np.ndarray, qd: np.ndarray, q_min: np.ndarray, q_max: np.ndarray, a_stop: np.ndarray,
                       joint_names: tuple[str, ...]) -> str | None:
    """Why the safety system stops a robot under torque control, or None: a joint moving towards a position limit
    that it could not stop before when braking at `a_stop`. (No joint runs faster than its speed limit: the drives
    do not drive it past it, as under position control.)

    Args:
        q, qd: (n,) measured positions [rad] and velocities [rad/s].
        q_min, q_max: (n,) position limits [rad].
        a_stop: (n,) the deceleration the check assumes [rad/s^2] (below what the robot brakes with, so that the
            arm stops within the limit).
        joint_names: n names, for the message.
    """
    reach = q + qd * np.abs(qd) / (2.0 * a_stop)  # where each joint would stop
    upper = (qd > 0.0) & (reach >= q_max)
    lower = (qd < 0.0) & (reach <= q_min)
    hit = np.flatnonzero(upper | lower)
    if hit.size == 0:
        return None
    i = int(hit[0])
    limit = q_max[i] if upper[i] else q_min[i]
    return (f'{joint_names[i]} would pass its position limit {limit:.4f} rad (position {q[i]:.4f} rad, '
            f'{qd[i]:.3f} rad/s)')
