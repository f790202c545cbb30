"""The build stage: joint positions, velocities and accelerations along the timed bead.

Per sample k (time t_k, arc length s_k): IK of the path pose by :meth:`Kinematics.ik_path` (for a
UR arm the closed-form solution in the branch of the first sample, checked and if need be refined
by Pinocchio; per-sample warm-started Newton for other kinematics), all samples at once; then, with
the LWA Jacobian J at the solution (batched over the samples),

    qd  = J^-1 [t sdot ; w_s sdot]
    qdd = J^-1 ([t sddot + k sdot^2 ; w_s sddot + w_s' sdot^2] - dJ/dt qd)

where t is the unit tangent, k the curvature vector, and w_s = d(orientation)/ds the
orientation's angular rate per metre [rad/m] (world axes), w_s' its derivative. The path
gives t and k analytically; w_s and w_s' are central differences (h = 1e-4 m) of the path's
own orientation interpolant, not of the samples, so their error is O(h^2), below 1e-8
relative. Velocities and accelerations are therefore exact derivatives of the planned
motion, not finite differences of the IK samples.

Where a joint would exceed ``velocity_margin * v_max`` or ``acceleration_margin * a_max``,
the stretch is re-timed at a lower speed (:class:`~ur_glue_planner.path.timing.SpeedLimit`),
smoothly, and reported as a :class:`Slowdown`; this repeats until every sample is within
the limits.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur_common.quaternions import matrix_from_quat, quat_from_matrix
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.orientation import rotation_vectors
from ur_glue_planner.path.glue_path import GluePath
from ur_glue_planner.path.timing import PathTiming, SpeedLimit, Usage, time_path

_H_ORIENT = 1e-4  # [m] stencil of the orientation derivatives


@dataclass(frozen=True)
class Slowdown:
    """A stretch re-timed below the commanded speed.

    Attributes:
        s_start, s_end: Arc-length range [m] of the reduced speed (transitions lie outside).
        factor: Speed there relative to the commanded speed (0, 1).
        joint: Name of the joint that needed it.
        kind: 'velocity' or 'acceleration'.
        demand: Largest |qd| [rad/s] or |qdd| [rad/s^2] of that joint at the earlier speed.
        limit: The limit it was held to (margin included), same unit.
    """

    s_start: float
    s_end: float
    factor: float
    joint: str
    kind: str
    demand: float
    limit: float


@dataclass(frozen=True, eq=False)
class JointPlan:
    """The bead in joint space, sampled at the timing's times.

    Attributes:
        joint_names: (n,) in the column order of q.
        times: (M,) [s] from the bead start.
        s: Arc length (M,) [m].
        q, qd, qdd: (M, n) [rad], [rad/s], [rad/s^2].
        q_s, q_ss: dq/ds (M, n) [rad/m] and d2q/ds2 (M, n) [rad/m^2], path properties:
            qd = q_s sdot and qdd = q_s sddot + q_ss sdot^2.
        tip_pos: Tip positions (M, 3) [m] (forward kinematics of q), world frame.
        tip_quat: Tip orientations (M, 4), w first.
        tcp_speed: |linear part of J qd| (M,) [m/s], the planned tip speed.
        ik_residual_pos: (M,) [m]; ik_residual_rot: (M,) [rad]; ik_iterations: (M,).
        ik_seconds: Wall time [s] of the final IK pass (all samples, velocities included).
        slowdowns: Stretches driven below the commanded speed.
        timing: The final time law.
        retimes: How many times the path was re-timed (each one a further IK pass).
    """

    joint_names: tuple[str, ...]
    times: np.ndarray
    s: np.ndarray
    q: np.ndarray
    q_s: np.ndarray
    q_ss: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tip_pos: np.ndarray
    tip_quat: np.ndarray
    tcp_speed: np.ndarray
    ik_residual_pos: np.ndarray
    ik_residual_rot: np.ndarray
    ik_iterations: np.ndarray
    ik_seconds: float
    slowdowns: tuple[Slowdown, ...]
    timing: PathTiming
    retimes: int


def orientations_and_rates(path: GluePath, s: np.ndarray, h: float = _H_ORIENT
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Path orientations (M, 3, 3) at s (M,) [m], with :func:`orientation_rates`, from one quaternion evaluation."""
    s = np.asarray(s, dtype=float)
    c = s if path.closed else np.clip(s, h, path.length - h)
    qm, q0, qp = path.quaternion(np.concatenate([c - h, c, c + h])).reshape(3, len(s), 4)
    q = q0.copy()
    ends = c != s  # only an open path's ends shift the stencil
    if np.any(ends):
        q[ends] = path.quaternion(s[ends])
    fwd = rotation_vectors(q0, qp) / h  # w_s at c + h/2
    back = rotation_vectors(qm, q0) / h  # w_s at c - h/2
    return matrix_from_quat(q), 0.5 * (fwd + back), (fwd - back) / h


def orientation_rates(path: GluePath, s: np.ndarray, h: float = _H_ORIENT) -> tuple[np.ndarray, np.ndarray]:
    """Angular rate w_s (M, 3) [rad/m] of the path orientation and its derivative (M, 3) [rad/m^2].

    World axes: d R / ds = [w_s]x R. Open paths shift the stencil inside [h, L - h].
    """
    return orientations_and_rates(path, s, h)[1:]


def _nearest_waypoint(path: GluePath, s: float) -> int:
    d = np.abs(path.waypoint_s - s)
    if path.closed:
        d = np.minimum(d, path.length - d)
    return int(np.argmin(d))


def _where(path: GluePath, k: int, s: float) -> str:
    return f"sample {k} (s = {s:.4f} m of {path.length:.4f} m, nearest waypoint {_nearest_waypoint(path, s)})"


@dataclass(frozen=True, eq=False)
class _Pass:
    q: np.ndarray
    q_s: np.ndarray
    q_ss: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    speed: np.ndarray
    res_p: np.ndarray
    res_r: np.ndarray
    iters: np.ndarray
    seconds: float


def _targets(pos: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """Poses (M, 4, 4) from positions (M, 3) and rotations (M, 3, 3)."""
    out = np.zeros((len(pos), 4, 4))
    out[:, :3, :3], out[:, :3, 3], out[:, 3, 3] = rot, pos, 1.0
    return out


def _solve_each(path: GluePath, s: np.ndarray, jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x (M, n) with jac[k] x[k] = rhs[k]; PlanningError naming the first singular sample."""
    try:
        return np.linalg.solve(jac, rhs[:, :, None])[:, :, 0]
    except np.linalg.LinAlgError as exc:
        k = next(k for k in range(len(jac)) if np.linalg.matrix_rank(jac[k]) < jac.shape[1])
        raise PlanningError(f"singular Jacobian at {_where(path, k, s[k])}") from exc


def _solve(path: GluePath, timing: PathTiming, kin: Kinematics, q_start: np.ndarray,
           v_max: np.ndarray, jump_safety: float, first_iterations: int, iterations: int) -> _Pass:
    s, sdot, sddot, times = timing.s, timing.sdot, timing.sddot, timing.times
    pos, tan, kvec = path.derivatives(s)
    rot, w_s, dw_s = orientations_and_rates(path, s)
    # task velocity = v_s sdot, task acceleration = v_s sddot + a_s sdot^2
    v_s, a_s = np.hstack([tan, w_s]), np.hstack([kvec, dw_s])
    t0 = time.perf_counter()
    ik = kin.ik_path(_targets(pos, rot), q_start, first_iterations=first_iterations, iterations=iterations)
    m = len(s) if ik.failed is None else ik.failed  # the samples solved, in order
    q = ik.q[:m]
    if ik.jacobian is not None:
        tip, tip_rot, jac = ik.position[:m], ik.rotation[:m], ik.jacobian[:m]
    else:
        tip, tip_rot, jac = kin.fk_jacobian_batch(q)
    q_s = _solve_each(path, s, jac, v_s[:m])
    # dJ/dt qd is quadratic in qd, so it equals sdot^2 times its value at qd = q_s
    q_ss = _solve_each(path, s, jac, a_s[:m] - kin.jacobian_dot_times_qd_batch(q, q_s, jac))
    qd = q_s * sdot[:m, None]
    qdd = q_s * sddot[:m, None] + q_ss * (sdot[:m] ** 2)[:, None]
    # a step far beyond what the joint speeds allow is a change of IK branch
    step = np.abs(np.diff(q, axis=0))
    allowed = jump_safety * np.diff(times[:m])[:, None] * np.maximum(
        v_max, np.maximum(np.abs(qd[1:]), np.abs(qd[:-1])))
    jumps = np.flatnonzero(np.any(step > allowed, axis=1))
    if jumps.size:
        k = int(jumps[0]) + 1
        bad = np.flatnonzero(step[k - 1] > allowed[k - 1])
        j = int(bad[np.argmax(step[k - 1, bad] / allowed[k - 1, bad])])
        raise PlanningError(f"joint {kin.joint_names[j]} jumps {step[k - 1, j]:.4f} rad between samples {k - 1} "
                            f"and {k} (allowed {allowed[k - 1, j]:.4f} rad) at {_where(path, k, s[k])}: "
                            f"the IK changed branch (singularity or joint limit)")
    if ik.failed is not None:
        k = ik.failed
        raise PlanningError(f"IK failed at {_where(path, k, s[k])}: residual {ik.residual_pos[k]:.2e} m, "
                            f"{ik.residual_rot[k]:.2e} rad after {ik.iterations[k]} iterations")
    speed = np.linalg.norm(np.einsum("mij,mj->mi", jac[:, :3], qd), axis=1)
    seconds = time.perf_counter() - t0
    return _Pass(q, q_s, q_ss, qd, qdd, tip, quat_from_matrix(tip_rot), speed,
                 ik.residual_pos, ik.residual_rot, ik.iterations, seconds)


def _runs(flag: np.ndarray) -> list[np.ndarray]:
    """Index runs (arrays of consecutive indices) of the True entries of ``flag``."""
    idx = np.flatnonzero(flag)
    return np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []


def _admissible_speed(sol: _Pass, v_lim: np.ndarray, a_lim: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest constant speed (M,) [m/s] per sample, the joint that sets it and whether by velocity."""
    qs, qss = np.abs(sol.q_s), np.abs(sol.q_ss)
    with np.errstate(divide="ignore"):
        by_v = np.where(qs > 0, v_lim / qs, np.inf)
        by_a = np.where(qss > 0, np.sqrt(a_lim / qss), np.inf)
    adm = np.minimum(by_v, by_a)
    joint = np.argmin(adm, axis=1)
    rows = np.arange(len(joint))
    return adm[rows, joint], joint, by_v[rows, joint] <= by_a[rows, joint]


def _usage_function(s: np.ndarray, q_s: np.ndarray, q_ss: np.ndarray, v_lim: np.ndarray,
                    a_lim: np.ndarray) -> Usage:
    """usage(s, sdot, sddot) from the path derivatives sampled at s (linear in between)."""
    grid, keep = np.unique(s, return_index=True)
    table = np.hstack([q_s[keep], q_ss[keep]])  # (G, 2n): both interpolated at once
    n = q_s.shape[1]

    def usage(x: np.ndarray, sdot: np.ndarray, sddot: np.ndarray) -> np.ndarray:
        # np.interp of every column: clamped to the end values outside the grid
        i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, len(grid) - 2)
        w = np.clip((x - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0)[:, None]
        ab = table[i] + w * (table[i + 1] - table[i])
        a, b = ab[:, :n], ab[:, n:]
        vel = np.abs(a * sdot[:, None]) / v_lim
        acc = np.abs(a * sddot[:, None] + b * (sdot ** 2)[:, None]) / a_lim
        return np.maximum(vel, acc).max(axis=1)

    return usage


def build_joint_plan(path: GluePath, timing: PathTiming, kin: Kinematics, q_start: np.ndarray, *,
                     a_max: float | Sequence[float] = 5.0, v_max: Sequence[float] | None = None,
                     velocity_margin: float = 0.95, acceleration_margin: float = 1.0,
                     jump_safety: float = 1.5, max_retimes: int = 4, slowdown_pad: float = 0.003,
                     first_iterations: int = 300, iterations: int = 20) -> JointPlan:
    """Joint trajectory of the bead, re-timed locally where joint limits demand it.

    A first pass at the nominal time law gives, per sample, the path derivatives q_s, q_ss
    (which do not depend on the time law), hence the largest constant speed each joint allows
    (``v_lim / |q_s|``, ``sqrt(a_lim / |q_ss|)``). Stretches where that speed is below the
    commanded one become slowdowns (2 % below the need, padded by ``slowdown_pad``), and every
    speed change, ramps included, is stretched until no joint exceeds its limits during it
    (``time_path``'s ``usage``, from q_s and q_ss). The re-timed path is solved again and
    checked; any remaining excess (sampling) is re-timed again, up to ``max_retimes``.

    The default margins: v_max is the hardware limit, so 5 % is kept for speed scaling and
    tracking; a_max (5 rad/s^2) is already MoveIt's conservative planning value.

    Args:
        path: The bead geometry (world frame).
        timing: Its nominal time law (:func:`~ur_glue_planner.path.timing.time_path`); re-timings
            keep its speed, dt and ramp time.
        kin: Kinematics of the tip frame.
        q_start: IK guess (n,) [rad] for the first sample; it picks the arm configuration.
        a_max: Joint acceleration limit(s) [rad/s^2].
        v_max: Joint velocity limits (n,) [rad/s]; default: the model's.
        velocity_margin, acceleration_margin: Fractions of the limits the plan may use.
        jump_safety: A joint step over ``jump_safety * dt * max(v_max, |qd|)`` between two
            samples is an IK branch change and fails the plan.
        max_retimes: Corrective re-timings after the first one.
        slowdown_pad: Each slowdown covers the offending samples plus this much [m] each side.
        first_iterations, iterations: IK iteration budgets, first and following samples.

    Raises:
        PlanningError: IK failure or a jump (naming sample, s, nearest waypoint, joint), or
            limits still exceeded after ``max_retimes`` re-timings.
    """
    vmax = kin.v_max if v_max is None else np.asarray(v_max, dtype=float)
    amax = np.broadcast_to(np.asarray(a_max, dtype=float), (kin.n,))
    v_lim, a_lim = velocity_margin * vmax, acceleration_margin * amax
    q0 = np.asarray(q_start, dtype=float)
    speed = timing.speed
    sol = _solve(path, timing, kin, q0, vmax, jump_safety, first_iterations, iterations)

    adm, adm_joint, adm_vel = _admissible_speed(sol, v_lim, a_lim)
    limits: list[SpeedLimit] = list(timing.limits)
    reports: list[Slowdown] = []
    for run in _runs(adm < speed):
        lo, hi = max(run[0] - 1, 0), min(run[-1] + 2, len(adm))  # the neighbours bound the dip too
        k = run[0] + int(np.argmin(adm[run]))
        factor = 0.98 * float(adm[lo:hi].min()) / speed
        a = max(float(timing.s[run[0]]) - slowdown_pad, 0.0)
        b = min(float(timing.s[run[-1]]) + slowdown_pad, timing.length)
        j, vel = int(adm_joint[k]), bool(adm_vel[k])
        demand = float(np.abs(sol.q_s[run, j]).max() * speed if vel else np.abs(sol.q_ss[run, j]).max() * speed ** 2)
        limits.append(SpeedLimit(a, b, factor))
        reports.append(Slowdown(a, b, factor, kin.joint_names[j], "velocity" if vel else "acceleration",
                                demand, float(v_lim[j] if vel else a_lim[j])))
    usage = _usage_function(timing.s, sol.q_s, sol.q_ss, v_lim, a_lim)
    retimes = 0
    over = np.maximum(np.abs(sol.qd) / v_lim, np.abs(sol.qdd) / a_lim).max() > 1.0
    if reports or over:
        timing = time_path(timing.length, speed, timing.dt, timing.ramp_time, limits, usage)
        sol = _solve(path, timing, kin, q0, vmax, jump_safety, first_iterations, iterations)
        retimes = 1

    while True:
        use = np.maximum(np.abs(sol.qd) / v_lim, np.sqrt(np.abs(sol.qdd) / a_lim))  # (M, n)
        over = use.max(axis=1) > 1.0
        if not np.any(over):
            break
        if retimes > max_retimes:
            k = int(np.argmax(use.max(axis=1)))
            j = int(np.argmax(use[k]))
            raise PlanningError(f"joint {kin.joint_names[j]} exceeds its limits (|qd| {abs(sol.qd[k, j]):.3f} of "
                                f"{v_lim[j]:.3f} rad/s, |qdd| {abs(sol.qdd[k, j]):.3f} of {a_lim[j]:.3f} rad/s^2) "
                                f"at {_where(path, k, timing.s[k])} after {retimes} re-timings")
        for run in _runs(over):
            k = run[0] + int(np.argmax(use[run].max(axis=1)))
            j = int(np.argmax(use[k]))
            factor = 0.98 * float(np.min(timing.sdot[run] / use[run].max(axis=1))) / speed
            a = max(float(timing.s[run[0]]) - slowdown_pad, 0.0)
            b = min(float(timing.s[run[-1]]) + slowdown_pad, timing.length)
            vel = abs(sol.qd[k, j]) / v_lim[j] >= np.sqrt(abs(sol.qdd[k, j]) / a_lim[j])
            limits.append(SpeedLimit(a, b, factor))
            reports.append(Slowdown(a, b, factor, kin.joint_names[j], "velocity" if vel else "acceleration",
                                    float(np.abs(sol.qd[run, j] if vel else sol.qdd[run, j]).max()),
                                    float(v_lim[j] if vel else a_lim[j])))
        timing = time_path(timing.length, speed, timing.dt, timing.ramp_time, limits, usage)
        sol = _solve(path, timing, kin, q0, vmax, jump_safety, first_iterations, iterations)
        retimes += 1

    return JointPlan(
        joint_names=kin.joint_names, times=timing.times, s=timing.s, q=sol.q, q_s=sol.q_s, q_ss=sol.q_ss,
        qd=sol.qd, qdd=sol.qdd, tip_pos=sol.pos, tip_quat=sol.quat, tcp_speed=sol.speed,
        ik_residual_pos=sol.res_p, ik_residual_rot=sol.res_r, ik_iterations=sol.iters, ik_seconds=sol.seconds,
        slowdowns=tuple(reports), timing=timing, retimes=retimes)
