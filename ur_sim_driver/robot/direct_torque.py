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
the compensation leaves: ``(1 - scale) x friction`` (:func:`felt_friction`). The drives keep every joint within its
speed limit, as in every mode; the safety system, which in the other modes watches the commanded position, watches
the measured motion against the position limits here (``safety.motion_limit_cause``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The External Control script ends its servo, speed and torque threads (no controller commands) with stopj(4.0).
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
