"""Seed 1's own bead trajectory (the MATLAB example's helper), kept as the baseline our planner is judged against.

Per segment between consecutive waypoints: time = distance / TCP speed rounded down to whole samples
(N = floor(d / (v dt)) intervals, so each segment runs slightly faster than v), poses interpolated linearly in
position and by SLERP in orientation at the sample times, IK per sample (warm-started from the previous
answer), then one minimum-jerk spline through all samples in joint space (piecewise quintic, C4, zero velocity
and acceleration at both ends and free in between: what minimising the integral of squared jerk through the
points gives), sampled at the same times for velocities and accelerations. Corners are not blended: the tip
turns on the spot at each waypoint, and the spline's overshoot there is what the baseline shows.
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.interpolate import make_interp_spline

from ur_common.quaternions import matrix_from_quat, quat_from_matrix
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.joint_trajectory import JointPlan
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.orientation import slerp
from ur_glue_planner.path.timing import PathTiming


def seed1_waypoints(points: np.ndarray, rots: np.ndarray, closed: bool, close_tolerance: float = 0.02
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The waypoint list the seed walks: as given; a closed bead whose last point is farther than
    ``close_tolerance`` [m] from the first gets the first point appended (seed 1's list closes within 6 mm)."""
    points, rots = np.asarray(points, dtype=float), np.asarray(rots, dtype=float)
    if closed and np.linalg.norm(points[-1] - points[0]) > close_tolerance:
        points, rots = np.vstack([points, points[:1]]), np.concatenate([rots, rots[:1]])
    return points, rots


def seed1_samples(points: np.ndarray, rots: np.ndarray, speed: float, dt: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Task-space samples of the seed's method.

    Returns:
        positions (M, 3) [m], rotations (M, 3, 3), segment index (M,) of each sample, and the segment speeds
        (K - 1,) [m/s] = d / (N dt).
    """
    quats = quat_from_matrix(rots)
    pos, quat, seg, speeds = [], [], [], []
    for i in range(len(points) - 1):
        d = float(np.linalg.norm(points[i + 1] - points[i]))
        n = max(1, math.floor(d / (speed * dt) + 1e-9))
        f = np.arange(n) / n
        pos.append(points[i] + f[:, None] * (points[i + 1] - points[i]))
        quat.append(slerp(np.broadcast_to(quats[i], (n, 4)), np.broadcast_to(quats[i + 1], (n, 4)), f))
        seg.append(np.full(n, i))
        speeds.append(d / (n * dt))
    pos.append(points[-1:])
    quat.append(quats[-1:])
    seg.append(np.array([len(points) - 2]))
    return (np.vstack(pos), matrix_from_quat(np.vstack(quat)), np.concatenate(seg), np.array(speeds))


def min_jerk_spline(times: np.ndarray, q: np.ndarray):
    """The minimum-jerk interpolant through (times, q) (M,), (M, n): a quintic spline, C4, at rest at both ends."""
    zero = np.zeros(q.shape[1])
    return make_interp_spline(times, q, k=5, bc_type=([(1, zero), (2, zero)], [(1, zero), (2, zero)]))


def seed1_bead(kin: Kinematics, points: np.ndarray, rots: np.ndarray, q_guess: np.ndarray, speed: float,
               dt: float, closed: bool) -> tuple[JointPlan, np.ndarray]:
    """The bead in joint space by seed 1's method.

    Args:
        kin: Tip kinematics. points (K, 3) [m], rots (K, 3, 3): the job's waypoints, world frame.
        q_guess: IK guess (n,) [rad] for the first sample. speed: TCP speed [m/s]. dt: sample time [s].
        closed: The job's bead is a loop (see :func:`seed1_waypoints`).

    Returns:
        The JointPlan (its timing describes the seed's piecewise constant speeds) and the polyline the
        seed intends, (K, 3) [m].

    Raises:
        PlanningError: IK fails at a sample.
    """
    wps, wrots = seed1_waypoints(points, rots, closed)
    pos, rot, seg, seg_speed = seed1_samples(wps, wrots, speed, dt)
    m = len(pos)
    times = np.arange(m) * dt
    q = np.zeros((m, kin.n))
    res_p, res_r, iters = np.zeros(m), np.zeros(m), np.zeros(m, dtype=int)
    target = np.eye(4)
    guess = np.asarray(q_guess, dtype=float)
    t0 = time.perf_counter()
    for k in range(m):
        target[:3, :3], target[:3, 3] = rot[k], pos[k]
        res = kin.ik(target, guess, max_iterations=300 if k == 0 else 50)
        if not res.converged:
            raise PlanningError(f"seed1: IK failed at sample {k} (segment {seg[k]}, waypoint {seg[k]} -> "
                                f"{seg[k] + 1}): residual {res.residual_pos:.2e} m, {res.residual_rot:.2e} rad")
        q[k], guess = res.q, res.q
        res_p[k], res_r[k], iters[k] = res.residual_pos, res.residual_rot, res.iterations
    seconds = time.perf_counter() - t0
    spline = min_jerk_spline(times, q)
    qd, qdd = spline(times, 1), spline(times, 2)
    tip, quat, tcp = np.zeros((m, 3)), np.zeros((m, 4)), np.zeros(m)
    for k in range(m):
        p, r, jac = kin.fk_jacobian(q[k])
        tip[k], quat[k], tcp[k] = p, quat_from_matrix(r), np.linalg.norm(jac[:3] @ qd[k])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(tip, axis=0), axis=1))])
    sdot = tcp
    sddot = np.gradient(sdot, times)
    with np.errstate(divide="ignore", invalid="ignore"):
        q_s = np.where(sdot[:, None] > 1e-9, qd / np.where(sdot[:, None] > 1e-9, sdot[:, None], 1.0), 0.0)
    q_ss = np.gradient(q_s, s, axis=0) if np.all(np.diff(s) > 0) else np.zeros_like(q_s)
    bounds = np.flatnonzero(np.diff(seg)) + 1
    piece_t = np.concatenate([[0.0], times[bounds], [times[-1]]])
    piece_s = np.concatenate([[0.0], s[bounds]])
    timing = PathTiming(length=float(s[-1]), speed=speed, dt=dt, ramp_time=0.0, end_extra=0.0,
                        duration=float(times[-1]), times=times, s=s, sdot=sdot, sddot=sddot,
                        levels=tuple((float(a), float(b), float(v)) for a, b, v in
                                     zip(piece_s, np.append(piece_s[1:], s[-1]), seg_speed)),
                        limits=(), piece_t=piece_t, piece_s=piece_s, piece_v0=seg_speed, piece_v1=seg_speed)
    plan = JointPlan(joint_names=kin.joint_names, times=times, s=s, q=q, q_s=q_s, q_ss=q_ss, qd=qd, qdd=qdd,
                     tip_pos=tip, tip_quat=quat, tcp_speed=tcp, ik_residual_pos=res_p, ik_residual_rot=res_r,
                     ik_iterations=iters, ik_seconds=seconds, slowdowns=(), timing=timing, retimes=0)
    return plan, wps
