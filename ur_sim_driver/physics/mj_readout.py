"""Reading the arm's measured state out of MjData, compiled: joint states, the TCP pose in the base frame and the
joint-space dynamics, each in one call.

Every control cycle reads these; done with numpy slices and MuJoCo's 3x3 routines through the Python bindings they
cost about 20 us a cycle (a microsecond or two per call and per small array). The kernels read MjData's arrays
(views that share its memory) directly, so they always see the current state.
"""
from __future__ import annotations

import math

from numba import njit, types

from ur_sim_driver.physics.numba_types import F8, IN1, IN2, INDEX, OUT1, OUT2, VOID


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


@njit(types.UniTuple(F8, 4)(F8, F8, F8, F8, F8, F8, F8, F8, F8), cache=True)
def mat_to_quat(m0, m1, m2, m3, m4, m5, m6, m7, m8):
    """Unit quaternion (w, x, y, z) of a row-major rotation matrix, as MuJoCo's mju_mat2Quat computes it: from the
    largest of its four components (numerically safe), then normalised."""
    if m0 + m4 + m8 > 0.0:
        w = 0.5 * math.sqrt(1.0 + m0 + m4 + m8)
        x, y, z = 0.25 * (m7 - m5) / w, 0.25 * (m2 - m6) / w, 0.25 * (m3 - m1) / w
    elif m0 > m4 and m0 > m8:
        x = 0.5 * math.sqrt(1.0 + m0 - m4 - m8)
        w, y, z = 0.25 * (m7 - m5) / x, 0.25 * (m1 + m3) / x, 0.25 * (m2 + m6) / x
    elif m4 > m8:
        y = 0.5 * math.sqrt(1.0 - m0 + m4 - m8)
        w, x, z = 0.25 * (m2 - m6) / y, 0.25 * (m1 + m3) / y, 0.25 * (m5 + m7) / y
    else:
        z = 0.5 * math.sqrt(1.0 - m0 - m4 + m8)
        w, x, y = 0.25 * (m3 - m1) / z, 0.25 * (m2 + m6) / z, 0.25 * (m5 + m7) / z
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    return w / norm, x / norm, y / norm, z / norm


@njit(VOID(IN1, IN1, IN1, IN1, OUT1), cache=True)
def read_pose(site_pos, site_mat, base_pos, base_mat, out):
    """out (7,): a site's position [m] and orientation (x, y, z, w) in a body's frame, from their world poses
    (positions (3,), row-major rotation matrices (9,))."""
    d0, d1, d2 = site_pos[0] - base_pos[0], site_pos[1] - base_pos[1], site_pos[2] - base_pos[2]
    for i in range(3):  # R_base^T (p_site - p_base)
        out[i] = base_mat[i] * d0 + base_mat[3 + i] * d1 + base_mat[6 + i] * d2
    r = [0.0] * 9  # R_base^T R_site, row-major
    for i in range(3):
        for j in range(3):
            r[3 * i + j] = (base_mat[i] * site_mat[j] + base_mat[3 + i] * site_mat[3 + j]
                            + base_mat[6 + i] * site_mat[6 + j])
    w, x, y, z = mat_to_quat(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8])
    out[3], out[4], out[5], out[6] = x, y, z, w
