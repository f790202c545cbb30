"""The joint velocities the robot's controller reports, counted from its joint encoders.

A UR controller does not measure velocity: it counts encoder ticks over each control period, so the velocity it
reports (RTDE ``actual_qd``, the driver's ``velocity`` state interface, ``/joint_states``) comes in steps of one tick
per period, and a joint at rest reports exactly 0.0 (URSim too). The simulated joint's velocity is continuous and,
after a motion, decays towards 0 without ever reaching it (3e-4 rad/s when a trajectory's result arrives, 1e-9 a
second later); reported as the controller would, it is rounded to whole ticks per period. Positions are reported
as simulated: one tick is far below anything a client compares.

UR does not publish its encoders' resolution. ``TICK`` is our estimate [EST]: 2^20 ticks per joint turn, a common
absolute joint encoder (6 urad, six times finer than the 0.03 mm repeatability of a UR5e at 0.85 m); one tick per
period is then 3.0e-3 rad/s at 500 Hz and 7.5e-4 rad/s at 125 Hz. The simulated joints settle to below half a step
within 0.01 s (e-Series) and 0.07 s (CB3, whose slower servo settles with a 37 ms time constant) of a trajectory's
end. No rclpy here.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import F8, IN1, OUT1

TICK = 2.0 * math.pi / 2**20  # [rad] one encoder tick [EST]


def velocity_step(control_dt: float) -> float:
    """The smallest nonzero velocity the controller reports [rad/s]: one tick per control period `control_dt` [s]."""
    return TICK / control_dt


def reported_velocity(qd: np.ndarray, control_dt: float) -> np.ndarray:
    """Joint velocities (n,) [rad/s] as the controller reports them: `qd` in whole ticks per period (0.0 at rest)."""
    return _to_ticks(np.asarray(qd, dtype=float), velocity_step(control_dt))


@njit(OUT1(IN1, F8), cache=True)
def _to_ticks(qd, step):
    # Every control cycle: compiled, as numpy's round, divide and multiply on 6 values cost about 5 us a cycle.
    out = np.empty(qd.shape[0])
    for i in range(qd.shape[0]):
        out[i] = np.round(qd[i] / step) * step + 0.0  # + 0.0: no -0.0
    return out
