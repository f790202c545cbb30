"""The values of a trajectory controller's ``controller_state`` message, packed in one compiled call.

The message (control_msgs/JointTrajectoryControllerState) carries eight (n,) arrays and the speed scaling factor
for the UR configuration (position command, position and velocity state), as upstream's ``publish_state`` fills
them (``joint_trajectory_controller.cpp`` 4.39+):

* reference: the trajectory at this cycle's trajectory time (``state_desired_``: in trajectory time, not scaled);
* feedback: the measured positions and velocities;
* error: reference - feedback positions; the velocity error stays 0.0, since ``compute_error_for_joint`` computes
  it only with a velocity or effort command interface;
* output: what the position command interfaces hold, the trajectory one update period later (``command_next_``);
  no velocities or efforts (no such command interfaces).

Its CDR template (cdr_template.py) takes them as one vector in the order of ``FIELDS``. Packing them with numpy
(a concatenate and a subtraction) cost about 2.4 us a cycle, this kernel about 0.5 us.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import F8, IN1, OUT1, VOID

#: (message part, its arrays) in the order of the packed vector; speed_scaling_factor follows them.
FIELDS = (('reference', ('positions', 'velocities', 'accelerations')), ('feedback', ('positions', 'velocities')),
          ('error', ('positions', 'velocities')), ('output', ('positions',)))
ARRAYS = sum(len(fields) for _, fields in FIELDS)  # 8


@njit(VOID(IN1, IN1, IN1, IN1, IN1, IN1, F8, OUT1), cache=True)
def _pack(q_ref, qd_ref, qdd_ref, q, qd, q_cmd, factor, out):  # pragma: no cover - compiled
    n = q.shape[0]
    for i in range(n):
        out[i] = q_ref[i]
        out[n + i] = qd_ref[i]
        out[2 * n + i] = qdd_ref[i]
        out[3 * n + i] = q[i]
        out[4 * n + i] = qd[i]
        out[5 * n + i] = q_ref[i] - q[i]
        out[6 * n + i] = 0.0  # no velocity error in a position-command configuration
        out[7 * n + i] = q_cmd[i]
    out[8 * n] = factor


def pack_state(q_ref: np.ndarray, qd_ref: np.ndarray, qdd_ref: np.ndarray, q: np.ndarray, qd: np.ndarray,
               q_cmd: np.ndarray, factor: float, out: np.ndarray) -> np.ndarray:
    """Write the controller_state vector into `out` (8 n + 1,) and return it.

    Args:
        q_ref, qd_ref, qdd_ref: (n,) reference [rad, rad/s, rad/s^2].
        q, qd: (n,) measured [rad, rad/s].
        q_cmd: (n,) the position command [rad].
        factor: the controller's own speed scaling factor.
    """
    _pack(q_ref, qd_ref, qdd_ref, q, qd, q_cmd, float(factor), out)
    return out
