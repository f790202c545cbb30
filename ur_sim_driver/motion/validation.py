"""Validation of incoming trajectories, shared by the action and the topic interface.

Each ``check_*`` function tests one rule and returns a reason (``str``) or None. The
reasons name the field, the value and the limit, so the ROS layer can log them or pass
them on as ``error_string`` unchanged.

:func:`validate_trajectory` runs the rules in the order of ros2_controllers'
``JointTrajectoryController::validate_trajectory_msg`` (Jazzy), so the first reason
matches the rule upstream would log first. It works on :class:`CommandArrays`: per-point
rules are evaluated for all points at once with numpy, and the per-point ``check_*``
function words the reason for the first point that fails, so 100,000 points validate in
milliseconds.

Always stricter than upstream: duplicate joint names, a negative first ``time_from_start``
and non-finite numbers. Stricter only when asked (the node's ``strict_limit_checks``
parameter passes the limits): positions outside the joint limits (``q_min``/``q_max``)
and velocities above them (``v_max``); upstream accepts those and the robot fails at run
time, which is what ur_sim does by default.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.motion.command_arrays import CommandArrays, from_command
from ur_sim_driver.motion.trajectory_types import TrajectoryCommand, TrajectoryPoints

# Upstream compares the last velocity against std::numeric_limits<float>::epsilon().
END_VELOCITY_EPSILON = float(np.finfo(np.float32).eps)
# Positions are compared to limits with this slack [rad] so that values which went
# through a degree/radian round trip are not rejected for a last-bit difference.
LIMIT_SLACK = 1e-9
_POS, _VEL, _ACC, _EFF = range(4)

Command = TrajectoryCommand | CommandArrays


def _arrays(cmd: Command) -> CommandArrays:
    return cmd if isinstance(cmd, CommandArrays) else from_command(cmd)


def check_joint_count(cmd: Command, joint_names_config: Sequence[str], allow_partial: bool) -> str | None:
    """Without partial goals, the command must name as many joints as the controller."""
    if allow_partial or len(cmd.joint_names) == len(joint_names_config):
        return None
    return (
        f"joint_names has {len(cmd.joint_names)} joints but the controller has "
        f"{len(joint_names_config)} ({', '.join(joint_names_config)}); partial goals are "
        "disabled (allow_partial_joints_goal is false)"
    )


def check_joint_names_present(cmd: Command) -> str | None:
    """joint_names must not be empty."""
    return None if cmd.joint_names else "joint_names is empty"


def check_points_present(cmd: CommandArrays) -> str | None:
    """points must not be empty."""
    return None if cmd.count else "points is empty: the trajectory has no points"


def check_joint_names_known(cmd: Command, joint_names_config: Sequence[str]) -> str | None:
    """Every joint name must be a controller joint (any order)."""
    for i, name in enumerate(cmd.joint_names):
        if name not in joint_names_config:
            return (
                f"joint_names[{i}] = '{name}' is not a controller joint "
                f"(expected names from: {', '.join(joint_names_config)})"
            )
    return None


def check_joint_names_unique(cmd: Command) -> str | None:
    """No joint may be named twice (upstream would silently map both to one joint)."""
    seen: dict[str, int] = {}
    for i, name in enumerate(cmd.joint_names):
        if name in seen:
            return f"joint_names[{i}] = '{name}' repeats joint_names[{seen[name]}]"
        seen[name] = i
    return None


def check_end_velocity(cmd: CommandArrays, allow_nonzero: bool) -> str | None:
    """The last point must not move, unless allow_nonzero_velocity_at_trajectory_end."""
    if allow_nonzero or not cmd.count:
        return None
    last = cmd.count - 1
    # zip stops at the shorter sequence: a size mismatch is reported by its own rule.
    for name, value in zip(cmd.joint_names, cmd.point_values(_VEL, last)):
        if abs(value) > END_VELOCITY_EPSILON:
            return (
                f"points[{last}].velocities[{name}] = {value:.6g} rad/s at the last point is "
                "not zero (allow_nonzero_velocity_at_trajectory_end is false)"
            )
    return None


def check_end_time(cmd: CommandArrays, now: float) -> str | None:
    """With a non-zero header stamp, the trajectory must not end before ``now`` [s]."""
    if cmd.header_stamp == 0.0 or not cmd.count:
        return None
    last = cmd.count - 1
    t_last = float(cmd.times[last])
    end = cmd.header_stamp + t_last
    if end < now:
        return (
            f"header.stamp ({cmd.header_stamp:.3f} s) + points[{last}].time_from_start "
            f"({t_last:.3f} s) = {end:.3f} s is before now ({now:.3f} s): the trajectory ends in the past"
        )
    return None


def check_time_from_start(cmd: Command, index: int) -> str | None:
    """time_from_start must strictly increase; the first may be 0 but not negative."""
    times = _arrays(cmd).times
    t = float(times[index])
    if index == 0:
        return f"points[0].time_from_start = {t:.6g} s is negative" if t < 0.0 else None
    previous = float(times[index - 1])
    if t <= previous:
        return (
            f"points[{index}].time_from_start = {t:.6g} s is not after "
            f"points[{index - 1}].time_from_start = {previous:.6g} s (times must strictly increase)"
        )
    return None


def check_point_sizes(cmd: Command, index: int) -> str | None:
    """positions must match joint_names; velocities/accelerations must match or be empty."""
    arrays = _arrays(cmd)
    n = len(arrays.joint_names)
    for field, size, may_be_empty in zip(("positions", "velocities", "accelerations"), arrays.sizes[index, :3],
                                         (False, True, True)):
        if size != n and not (may_be_empty and size == 0):
            allowed = f"{n} (or 0)" if may_be_empty else f"{n}"
            return f"points[{index}].{field} has {size} values but joint_names has {n} joints (expected {allowed})"
    return None


def check_no_effort(cmd: CommandArrays, index: int) -> str | None:
    """Effort trajectories are rejected, as upstream does for a position-controlled arm."""
    count = int(cmd.sizes[index, _EFF])
    if count:
        return (
            f"points[{index}].effort is given ({count} values); trajectories with "
            "effort are not supported, leave effort empty"
        )
    return None


def check_finite(cmd: CommandArrays, index: int) -> str | None:
    """time_from_start, positions, velocities and accelerations must be finite."""
    t = float(cmd.times[index])
    if not np.isfinite(t):
        return f"points[{index}].time_from_start = {t} s is not finite"
    for field, name in ((_POS, "positions"), (_VEL, "velocities"), (_ACC, "accelerations")):
        for joint, value in zip(cmd.joint_names, cmd.point_values(field, index)):
            if not np.isfinite(value):
                return f"points[{index}].{name}[{joint}] = {value} is not finite"
    return None


def check_joint_limits(cmd: CommandArrays, index: int, columns: np.ndarray, q_min: np.ndarray,
                       q_max: np.ndarray) -> str | None:
    """Positions must lie in [q_min, q_max] (config order, (n,) [rad]); `columns` maps sender to config order."""
    for name, j, value in zip(cmd.joint_names, columns, cmd.point_values(_POS, index)):
        lo, hi = float(q_min[j]), float(q_max[j])
        if not lo - LIMIT_SLACK <= value <= hi + LIMIT_SLACK:
            return (f"points[{index}].positions[{name}] = {value:.6g} rad is outside the joint limits "
                    f"[{lo:.4f}, {hi:.4f}]")
    return None


def check_velocity_limits(cmd: CommandArrays, index: int, columns: np.ndarray, v_max: np.ndarray) -> str | None:
    """Given velocities, and the mean velocity of the segment ending at point `index`, must not exceed v_max.

    The segment from the measured state to point 0 is not checked: upstream lets a first point at time 0
    make the reference jump, which the path tolerance then reports.

    Args:
        columns: (n,) config index of each sender joint.
        v_max: (n,) velocity limits, config order [rad/s].
    """
    for name, j, value in zip(cmd.joint_names, columns, cmd.point_values(_VEL, index)):
        limit = float(v_max[j])
        if abs(value) > limit + LIMIT_SLACK:
            return (f"points[{index}].velocities[{name}] = {value:.6g} rad/s exceeds the velocity limit "
                    f"{limit:.4f} rad/s")
    if index == 0:
        return None
    dt = float(cmd.times[index] - cmd.times[index - 1])
    previous = cmd.point_values(_POS, index - 1)
    for name, j, q1, q0 in zip(cmd.joint_names, columns, cmd.point_values(_POS, index), previous):
        limit = float(v_max[j])
        mean = abs(q1 - q0) / dt
        if mean > limit + LIMIT_SLACK:
            return (f"points[{index - 1}] -> points[{index}] moves {name} at {mean:.6g} rad/s on average, above "
                    f"its velocity limit {limit:.4f} rad/s (make time_from_start longer)")
    return None


def _first(mask: np.ndarray) -> int | None:
    hits = np.flatnonzero(mask)
    return int(hits[0]) if hits.size else None


def _point_rule_failures(cmd: CommandArrays) -> np.ndarray:
    """(N,) bool: points failing the time, size or effort rule (upstream checks these point by point)."""
    n = len(cmd.joint_names)
    t, sizes = cmd.times, cmd.sizes
    bad = np.zeros(cmd.count, dtype=bool)
    bad[0] = t[0] < 0.0
    bad[1:] = t[1:] <= t[:-1]
    bad |= sizes[:, _POS] != n
    for field in (_VEL, _ACC):
        bad |= (sizes[:, field] != n) & (sizes[:, field] != 0)
    return bad | (sizes[:, _EFF] > 0)


def _value_failures(cmd: CommandArrays, columns: np.ndarray, q_min, q_max, v_max) -> np.ndarray:
    """(N,) bool: points with a non-finite value, or (when limits are given) outside the limits."""
    q, _ = cmd.block(_POS)
    v, has_v = cmd.block(_VEL)
    a, _ = cmd.block(_ACC)
    bad = ~np.isfinite(cmd.times) | ~np.isfinite(q).all(1) | ~np.isfinite(v).all(1) | ~np.isfinite(a).all(1)
    if q_min is not None and q_max is not None:
        bad |= ((q < q_min[columns] - LIMIT_SLACK) | (q > q_max[columns] + LIMIT_SLACK)).any(1)
    if v_max is not None:
        limit = v_max[columns] + LIMIT_SLACK
        bad |= (has_v[:, None] & (np.abs(v) > limit)).any(1)
        with np.errstate(divide='ignore', invalid='ignore'):
            mean = np.abs(np.diff(q, axis=0)) / np.diff(cmd.times)[:, None]
        bad[1:] |= (mean > limit).any(1)
    return bad


def validate_trajectory(
    cmd: Command,
    *,
    joint_names_config: Sequence[str],
    now: float,
    q_min: np.ndarray | None = None,
    q_max: np.ndarray | None = None,
    allow_partial: bool = False,
    allow_nonzero_end_velocity: bool = False,
    v_max: np.ndarray | None = None,
) -> str | None:
    """Run every rule in upstream order and return the first reason, or None if valid.

    Args:
        cmd: The command as received (:class:`TrajectoryCommand` or :class:`CommandArrays`).
        joint_names_config: n controller joint names.
        now: Current time on the controller's clock [s].
        q_min, q_max: (n,) position limits, config order [rad]; None skips the limit check.
        allow_partial: Upstream ``allow_partial_joints_goal``.
        allow_nonzero_end_velocity: Upstream ``allow_nonzero_velocity_at_trajectory_end``.
        v_max: (n,) velocity limits, config order [rad/s]; None skips the velocity check.
    """
    arrays = _arrays(cmd)
    reason = (
        check_joint_count(arrays, joint_names_config, allow_partial)
        or check_joint_names_present(arrays)
        or check_points_present(arrays)
        or check_joint_names_known(arrays, joint_names_config)
        or check_joint_names_unique(arrays)
        or check_end_velocity(arrays, allow_nonzero_end_velocity)
        or check_end_time(arrays, now)
    )
    if reason:
        return reason
    # Upstream checks time, sizes and effort point by point; ours follow once all pass.
    i = _first(_point_rule_failures(arrays))
    if i is not None:
        return check_time_from_start(arrays, i) or check_point_sizes(arrays, i) or check_no_effort(arrays, i)
    config = list(joint_names_config)
    columns = np.array([config.index(name) for name in arrays.joint_names])
    i = _first(_value_failures(arrays, columns, q_min, q_max, v_max))
    if i is None:
        return None
    reason = check_finite(arrays, i)
    if reason is None and q_min is not None and q_max is not None:
        reason = check_joint_limits(arrays, i, columns, q_min, q_max)
    if reason is None and v_max is not None:
        reason = check_velocity_limits(arrays, i, columns, v_max)
    return reason


def map_to_config_order(
    cmd: Command, joint_names_config: Sequence[str], current_positions: np.ndarray
) -> TrajectoryPoints:
    """Reorder a validated command to controller order and fill joints it leaves out.

    As upstream's ``fill_partial_goal``: a joint missing from a partial goal holds
    ``current_positions`` at every point with zero velocity and acceleration (upstream
    uses the last position command when there is one, else the measured position; the
    caller chooses which to pass).

    Args:
        cmd: A command that passed :func:`validate_trajectory`.
        joint_names_config: n controller joint names.
        current_positions: (n,) hold positions for missing joints, config order [rad].

    Raises:
        TrajectoryError: The command was not validated (unknown names or bad sizes).
    """
    arrays = _arrays(cmd)
    config = list(joint_names_config)
    n, count = len(config), arrays.count
    reason = check_joint_names_known(arrays, config) or check_joint_names_unique(arrays) or (
        None if count else "points is empty")
    if reason is None:
        i = _first(_point_rule_failures(arrays) & (arrays.sizes[:, _EFF] == 0))
        reason = None if i is None else check_point_sizes(arrays, i)
    if reason:
        raise TrajectoryError(f"cannot map an invalid trajectory: {reason}")
    hold = np.asarray(current_positions, dtype=float)
    if hold.shape != (n,):
        raise TrajectoryError(f"current_positions has shape {hold.shape}, expected ({n},)")

    columns = [config.index(name) for name in arrays.joint_names]
    blocks = [arrays.block(field) for field in (_POS, _VEL, _ACC)]
    positions = np.tile(hold, (count, 1))
    positions[:, columns] = blocks[0][0]
    velocities = np.zeros((count, n))
    velocities[:, columns] = blocks[1][0]
    accelerations = np.zeros((count, n))
    accelerations[:, columns] = blocks[2][0]
    return TrajectoryPoints(
        joint_names=tuple(config),
        times=arrays.times.copy(),
        positions=positions,
        velocities=velocities,
        accelerations=accelerations,
        has_velocities=blocks[1][1],
        has_accelerations=blocks[2][1],
        header_stamp=arrays.header_stamp,
    )
