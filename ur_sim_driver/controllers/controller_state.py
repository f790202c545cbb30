"""The values of a trajectory controller's ``controller_state`` message, packed in one compiled call.

The message (control_msgs/JointTrajectoryControllerState) carries ten (n,) arrays and the speed scaling factor;
its CDR template (cdr_template.py) takes them as one vector in the order of ``FIELDS``. Packing them with numpy
(a concatenate of eleven pieces and two subtractions) cost about 2.4 us a cycle, this kernel about 0.5 us.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import F8, IN1, OUT1, VOID

#: (message part, its arrays) in the order of the packed vector; speed_scaling_factor follows them.
FIELDS = (('reference', ('positions', 'velocities', 'accelerations')), ('feedback', ('positions', 'velocities')),
          ('error', ('positions', 'velocities')), ('output', ('positions', 'velocities', 'effort')))
ARRAYS = sum(len(fields) for _, fields in FIELDS)  # 10


@njit(VOID(IN1, IN1, IN1, IN1, IN1, IN1, F8, OUT1), cache=True)
def _pack(q_ref, qd_ref, qdd_ref, q, qd, effort, factor, out):  # pragma: no cover - compiled
    n = q.shape[0]
    for i in range(n):
        out[i] = q_ref[i]
        out[n + i] = qd_ref[i]
        out[2 * n + i] = qdd_ref[i]
        out[3 * n + i] = q[i]
        out[4 * n + i] = qd[i]
        out[5 * n + i] = q_ref[i] - q[i]
        out[6 * n + i] = qd_ref[i] - qd[i]
        out[7 * n + i] = q_ref[i]  # output: the reference the joints are commanded (position interfaces)
        out[8 * n + i] = qd_ref[i]
        out[9 * n + i] = effort[i]
    out[10 * n] = factor


def pack_state(q_ref: np.ndarray, qd_ref: np.ndarray, qdd_ref: np.ndarray, q: np.ndarray, qd: np.ndarray,
               effort: np.ndarray, factor: float, out: np.ndarray) -> np.ndarray:
    """Write the controller_state vector into `out` (10 n + 1,) and return it.

    Args:
        q_ref, qd_ref, qdd_ref: (n,) reference [rad, rad/s, rad/s^2].
        q, qd: (n,) measured [rad, rad/s].
        effort: (n,) joint efforts [N m].
        factor: the speed scaling factor the controller advances trajectory time by.
    """
    _pack(q_ref, qd_ref, qdd_ref, q, qd, effort, float(factor), out)
    return out
