"""Moves around the bead: a jerk-limited joint move to it, and straight moves along the tool axis.

- :func:`joint_move`: Ruckig from the current joint state (q, qd, qdd) to a joint goal at rest,
  time-synchronised, with the type's velocity limits (times ``velocity_scale``), the
  acceleration limit and a jerk limit; its duration is at least ``min_duration`` (seed 1
  moves to the first waypoint in 4 s) and a whole number of samples.
- :func:`tool_axis_move`: the tip moves in a straight line along the tool axis with fixed
  orientation, from rest to rest on a quintic time law (the descent onto the first bead point
  and the lift-off after the last one). Its joint velocities and accelerations come from the
  Jacobian like the bead's, so the moves join the bead without a step.

Jerk limit: UR publishes none and ``ur_moveit_config`` sets none; we use
``DEFAULT_JERK_FACTOR * a_max`` per second (25 rad/s^3 for 5 rad/s^2), i.e. full acceleration
is reached in 0.2 s (25 cycles of a CB3 controller), smooth enough for the trajectory
controller's spline interpolation to follow without overshoot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from ruckig import DurationDiscretization, InputParameter, Result, Ruckig, RuckigError, Trajectory

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.kinematics import Kinematics

DEFAULT_JERK_FACTOR = 5.0  # [1/s] jerk limit = factor * acceleration limit


@dataclass(frozen=True, eq=False)
class JointSegment:
    """A sampled joint trajectory, starting at time 0.

    Attributes:
        name: What it is for, e.g. 'approach', 'descent', 'retreat'.
        times: (K,) [s], uniform dt except possibly the last interval.
        q, qd, qdd: (K, n) [rad], [rad/s], [rad/s^2].
    """

    name: str
    times: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray

    @property
    def duration(self) -> float:
        """Length [s]."""
        return float(self.times[-1])


def joint_move(q0: np.ndarray, q_goal: np.ndarray, v_max: np.ndarray, a_max: float | np.ndarray, dt: float, *,
               qd0: np.ndarray | None = None, qdd0: np.ndarray | None = None, j_max: float | np.ndarray | None = None,
               velocity_scale: float = 1.0, min_duration: float = 0.0, q_min: np.ndarray | None = None,
               q_max: np.ndarray | None = None, name: str = "approach") -> JointSegment:
    """Jerk-limited, time-synchronised move to ``q_goal`` at rest (Ruckig).

    Args:
        q0, qd0, qdd0: Current state (n,) [rad], [rad/s], [rad/s^2] (velocity and acceleration 0 if None).
        q_goal: Goal (n,) [rad], reached with zero velocity and acceleration.
        v_max: Velocity limits (n,) [rad/s], scaled by ``velocity_scale``.
        a_max: Acceleration limit(s) [rad/s^2].
        dt: Sample time [s]; the duration is a multiple of it.
        j_max: Jerk limit(s) [rad/s^3]; default ``DEFAULT_JERK_FACTOR * a_max``.
        velocity_scale: Fraction (0, 1] of v_max to use.
        min_duration: Shortest duration [s].
        q_min, q_max: Position limits (n,) [rad] the move must stay within, if given (checked
            on the exact extrema; Ruckig's community version does not plan with them).
        name: Label of the segment.

    Raises:
        PlanningError: Ruckig finds no trajectory, or it leaves the position limits.
    """
    q0 = np.asarray(q0, dtype=float)
    n = len(q0)
    zeros = np.zeros(n)
    a_lim = np.broadcast_to(np.asarray(a_max, dtype=float), (n,))
    j_lim = DEFAULT_JERK_FACTOR * a_lim if j_max is None else np.broadcast_to(np.asarray(j_max, dtype=float), (n,))
    if not 0.0 < velocity_scale <= 1.0:
        raise ValueError(f"velocity_scale {velocity_scale} must be in (0, 1]")
    for what, lim in (("v_max", np.asarray(v_max, dtype=float)), ("a_max", a_lim), ("j_max", j_lim)):
        if not np.all(lim > 0.0):
            raise ValueError(f"{what} {lim.tolist()} must be > 0")
    otg = Ruckig(n, dt)
    inp = InputParameter(n)
    inp.current_position = q0.tolist()
    inp.current_velocity = (zeros if qd0 is None else np.asarray(qd0, dtype=float)).tolist()
    inp.current_acceleration = (zeros if qdd0 is None else np.asarray(qdd0, dtype=float)).tolist()
    inp.target_position = np.asarray(q_goal, dtype=float).tolist()
    inp.target_velocity = zeros.tolist()
    inp.target_acceleration = zeros.tolist()
    inp.max_velocity = (velocity_scale * np.asarray(v_max, dtype=float)).tolist()
    inp.max_acceleration = a_lim.tolist()
    inp.max_jerk = j_lim.tolist()
    if min_duration > 0.0:
        inp.minimum_duration = float(min_duration)
    # the duration becomes a whole number of samples: the last sample lands on the goal
    inp.duration_discretization = DurationDiscretization.Discrete
    traj = Trajectory(n)
    try:
        result = otg.calculate(inp, traj)
    except RuckigError as exc:
        raise PlanningError(f"{name}: Ruckig rejected the input: {str(exc).strip()}") from exc
    if result not in (Result.Working, Result.Finished):
        raise PlanningError(f"{name}: Ruckig found no trajectory from {np.round(q0, 4).tolist()} to "
                            f"{np.round(np.asarray(q_goal), 4).tolist()} rad ({result.name})")
    if q_min is not None and q_max is not None:
        # Ruckig (community) does not take position limits: check the exact extrema instead
        low = np.array([e.min for e in traj.position_extrema])
        high = np.array([e.max for e in traj.position_extrema])
        bad = np.flatnonzero((low < np.asarray(q_min) - 1e-9) | (high > np.asarray(q_max) + 1e-9))
        if bad.size:
            j = int(bad[0])
            raise PlanningError(f"{name}: joint {j} would leave its limits [{q_min[j]:.4f}, {q_max[j]:.4f}] rad "
                                f"(moves within [{low[j]:.4f}, {high[j]:.4f}])")
    duration = float(traj.duration)
    times = np.arange(round(duration / dt) + 1) * dt  # a single sample if already at rest on the goal
    times[-1] = duration
    q, qd, qdd = (np.array(x) for x in zip(*(traj.at_time(float(t)) for t in times)))
    return JointSegment(name, times, q, qd, qdd)


def _quintic(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest-to-rest unit profile and its first two derivatives in tau."""
    return (tau ** 3 * (10.0 + tau * (-15.0 + 6.0 * tau)), 30.0 * tau ** 2 * (1.0 - tau) ** 2,
            60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau))


def tool_axis_move(kin: Kinematics, q_anchor: np.ndarray, pose_anchor: np.ndarray, axis: np.ndarray,
                   distance: float, speed: float, dt: float, *, toward_anchor: bool,
                   name: str) -> JointSegment:
    """Straight tip move of ``distance`` [m] along ``-axis`` (away from the work) from/to an anchor.

    The anchor (a bead end: joint positions q_anchor (n,), tip pose (4, 4)) is the end of the
    move if ``toward_anchor`` (descent) or its start (retreat). IK runs outward from the
    anchor, warm-started, so the move stays in the anchor's arm configuration and meets it
    exactly. The time law is a quintic from rest to rest whose peak speed is ``speed``.

    Args:
        kin: Tip kinematics.
        axis: Tool axis (3,) in the tip frame (the direction the nozzle points).
        speed: Peak tip speed [m/s].
        dt: Sample time [s]; the duration is a whole number of samples.

    Raises:
        PlanningError: IK fails along the way.
    """
    if not (distance > 0.0 and speed > 0.0):
        raise ValueError(f"distance {distance} m and speed {speed} m/s must be > 0")
    rot, p0 = pose_anchor[:3, :3], pose_anchor[:3, 3]
    u = rot @ (np.asarray(axis, dtype=float) / np.linalg.norm(axis))
    duration = math.ceil(1.875 * distance / speed / dt - 1e-9) * dt
    times = np.arange(round(duration / dt) + 1) * dt
    tau = times / duration
    shape, dshape, ddshape = _quintic(tau)
    # arc length away from the anchor, and its time derivatives, in the move's own time
    if toward_anchor:
        d, dd, ddd = distance * (1.0 - shape), -distance * dshape / duration, -distance * ddshape / duration ** 2
    else:
        d, dd, ddd = distance * shape, distance * dshape / duration, distance * ddshape / duration ** 2
    # IK runs outward from the anchor, so the move stays in its arm configuration
    order = np.arange(len(times))[::-1] if toward_anchor else np.arange(len(times))
    targets = np.broadcast_to(np.asarray(pose_anchor, dtype=float), (len(times), 4, 4)).copy()
    targets[:, :3, 3] = p0 - d[order, None] * u
    ik = kin.ik_path(targets, np.asarray(q_anchor, dtype=float), first_iterations=200, iterations=200)
    if ik.failed is not None:
        i = int(order[ik.failed])
        raise PlanningError(f"IK failed for {name} sample {i} ({d[i]:.4f} m off): residual "
                            f"{ik.residual_pos[ik.failed]:.3e} m, {ik.residual_rot[ik.failed]:.3e} rad after "
                            f"{ik.iterations[ik.failed]} iterations (frame {kin.frame}, "
                            f"q = {np.round(ik.q[ik.failed], 4).tolist()})")
    q, jac = np.empty_like(ik.q), np.empty((len(times), 6, kin.n))
    q[order] = ik.q  # the anchor's own sample is q_anchor: IK starts there on its pose
    jac[order] = kin.fk_jacobian_batch(ik.q)[2] if ik.jacobian is None else ik.jacobian
    zero = np.zeros((len(times), 3))
    qd = np.linalg.solve(jac, np.hstack([-u * dd[:, None], zero])[:, :, None])[:, :, 0]
    qdd = np.linalg.solve(jac, (np.hstack([-u * ddd[:, None], zero])
                                - kin.jacobian_dot_times_qd_batch(q, qd, jac))[:, :, None])[:, :, 0]
    return JointSegment(name, times, q, qd, qdd)


def offset_pose(pose: np.ndarray, axis: np.ndarray, distance: float) -> np.ndarray:
    """``pose`` (4, 4) moved back by ``distance`` [m] against the tool ``axis`` (3,) (tip frame)."""
    out = np.array(pose, dtype=float)
    out[:3, 3] -= distance * (out[:3, :3] @ (np.asarray(axis, dtype=float) / np.linalg.norm(axis)))
    return out
