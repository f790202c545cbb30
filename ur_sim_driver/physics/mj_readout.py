"""Reading the arm's measured state out of MjData, compiled: joint states and the joint-space dynamics, each in
one call, and the TCP pose from MuJoCo's two frame sensors (see ``description/mjcf.py``).

Every control cycle reads these; done with numpy slices and MuJoCo's 3x3 routines through the Python bindings they
cost about 20 us a cycle (a microsecond or two per call and per small array). The kernels read MjData's arrays
(views that share its memory) directly, so they always see the current state.
"""
from __future__ import annotations

from numba import njit

from ur_sim_driver.physics.numba_types import I8, IN1, IN2, INDEX, OUT1, OUT2, VOID


@njit(VOID(IN1, IN1, IN1, INDEX, INDEX, INDEX, OUT2), cache=True)
def read_joints(qpos, qvel, actuator_force, i_qpos, i_dof, i_act, out):
    """out (3, n): positions [rad], velocities [rad/s] and actuator torques [N m] of the joints at the indices."""
    for k in range(i_qpos.shape[0]):
        out[0, k] = qpos[i_qpos[k]]
        out[1, k] = qvel[i_dof[k]]
        out[2, k] = actuator_force[i_act[k]]


@njit(VOID(IN2, IN1, IN1, INDEX, OUT2, OUT1), cache=True)
def read_dynamics(full_mass, qfrc_bias, qfrc_passive, i_dof, mass, bias):
    """mass (n, n) [kg m^2]: the joints' block of the full M (nv, nv); bias (n,) [N m]: gravity + Coriolis - passive."""
    n = i_dof.shape[0]
    for a in range(n):
        bias[a] = qfrc_bias[i_dof[a]] - qfrc_passive[i_dof[a]]
        for b in range(n):
            mass[a, b] = full_mass[i_dof[a], i_dof[b]]


@njit(VOID(IN1, I8, I8, OUT1), cache=True)
def read_pose(sensordata, position, orientation, out):
    """out (7,): the position (3,) [m] at sensordata[position:] and the quaternion (x, y, z, w) with w >= 0 from the
    (w, x, y, z) at sensordata[orientation:] (the driver's sign: it builds the quaternion from an angle in [0, pi])."""
    for k in range(3):
        out[k] = sensordata[position + k]
    sign = 1.0 if sensordata[orientation] >= 0.0 else -1.0
    for k in range(3):
        out[3 + k] = sign * sensordata[orientation + 1 + k]
    out[6] = sign * sensordata[orientation]
