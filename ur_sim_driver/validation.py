"""Validation of incoming trajectories, shared by the action and the topic interface.

Each ``check_*`` function tests one rule and returns a reason (``str``) or None. The
reasons name the field, the value and the limit, so the ROS layer can log them or pass
them on as ``error_string`` unchanged.

:func:`validate_trajectory` runs the rules in the order of ros2_controllers'
``JointTrajectoryController::validate_trajectory_msg`` (Jazzy), so the first reason
matches the rule upstream would log first. Rules we add (stricter than upstream):
duplicate joint names, negative ``time_from_start``, non-finite numbers and positions
outside the joint limits.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.trajectory_types import TrajectoryCommand, TrajectoryPoints

# Upstream compares the last velocity against std::numeric_limits<float>::epsilon().
END_VELOCITY_EPSILON = float(np.finfo(np.float32).eps)
# Positions are compared to limits with this slack [rad] so that values which went
# through a degree/radian round trip are not rejected for a last-bit difference.
LIMIT_SLACK = 1e-9


def check_joint_count(cmd: TrajectoryCommand, joint_names_config: Sequence[str], allow_partial: bool) -> str | None:
    """Without partial goals, the command must name as many joints as the controller."""
    if allow_partial or len(cmd.joint_names) == len(joint_names_config):
        return None
    return (
        f"joint_names has {len(cmd.joint_names)} joints but the controller has "
        f"{len(joint_names_config)} ({', '.join(joint_names_config)}); partial goals are "
        "disabled (allow_partial_joints_goal is false)"
    )


def check_joint_names_present(cmd: TrajectoryCommand) -> str | None:
    """joint_names must not be empty."""
    return None if cmd.joint_names else "joint_names is empty"


def check_points_present(cmd: TrajectoryCommand) -> str | None:
    """points must not be empty."""
    return None if cmd.points else "points is empty: the trajectory has no points"


def check_joint_names_known(cmd: TrajectoryCommand, joint_names_config: Sequence[str]) -> str | None:
    """Every joint name must be a controller joint (any order)."""
    for i, name in enumerate(cmd.joint_names):
        if name not in joint_names_config:
            return (
                f"joint_names[{i}] = '{name}' is not a controller joint "
                f"(expected names from: {', '.join(joint_names_config)})"
            )
    return None


def check_joint_names_unique(cmd: TrajectoryCommand) -> str | None:
    """No joint may be named twice (upstream would silently map both to one joint)."""
    seen: dict[str, int] = {}
    for i, name in enumerate(cmd.joint_names):
        if name in seen:
            return f"joint_names[{i}] = '{name}' repeats joint_names[{seen[name]}]"
        seen[name] = i
    return None


def check_end_velocity(cmd: TrajectoryCommand, allow_nonzero: bool) -> str | None:
    """The last point must not move, unless allow_nonzero_velocity_at_trajectory_end."""
    if allow_nonzero or not cmd.points:
        return None
    last = len(cmd.points) - 1
    # zip stops at the shorter sequence: a size mismatch is reported by its own rule.
    for name, value in zip(cmd.joint_names, cmd.points[last].velocities):
        if abs(value) > END_VELOCITY_EPSILON:
            return (
                f"points[{last}].velocities[{name}] = {value:.6g} rad/s at the last point is "
                "not zero (allow_nonzero_velocity_at_trajectory_end is false)"
            )
    return None


def check_end_time(cmd: TrajectoryCommand, now: float) -> str | None:
    """With a non-zero header stamp, the trajectory must not end before ``now`` [s]."""
    if cmd.header_stamp == 0.0 or not cmd.points:
        return None
    last = len(cmd.points) - 1
    end = cmd.header_stamp + cmd.points[last].time_from_start
    if end < now:
        return (
            f"header.stamp ({cmd.header_stamp:.3f} s) + points[{last}].time_from_start "
            f"({cmd.points[last].time_from_start:.3f} s) = {end:.3f} s is before now "
            f"({now:.3f} s): the trajectory ends in the past"
        )
    return None


def check_time_from_start(cmd: TrajectoryCommand, index: int) -> str | None:
    """time_from_start must strictly increase; the first may be 0 but not negative."""
    t = cmd.points[index].time_from_start
    if index == 0:
        if t < 0.0:
            return f"points[0].time_from_start = {t:.6g} s is negative"
        return None
    previous = cmd.points[index - 1].time_from_start
    if t <= previous:
        return (
            f"points[{index}].time_from_start = {t:.6g} s is not after "
            f"points[{index - 1}].time_from_start = {previous:.6g} s (times must strictly increase)"
        )
    return None


def check_point_sizes(cmd: TrajectoryCommand, index: int) -> str | None:
    """positions must match joint_names; velocities/accelerations must match or be empty."""
    point, n = cmd.points[index], len(cmd.joint_names)
    for field, values, may_be_empty in (
        ("positions", point.positions, False),
        ("velocities", point.velocities, True),
        ("accelerations", point.accelerations, True),
    ):
        if len(values) != n and not (may_be_empty and not values):
            allowed = f"{n} (or 0)" if may_be_empty else f"{n}"
            return (
                f"points[{index}].{field} has {len(values)} values but joint_names has {n} joints (expected {allowed})"
            )
    return None


def check_no_effort(cmd: TrajectoryCommand, index: int) -> str | None:
    """Effort trajectories are rejected, as upstream does for a position-controlled arm."""
    effort = cmd.points[index].effort
    if effort:
        return (
            f"points[{index}].effort is given ({len(effort)} values); trajectories with "
            "effort are not supported, leave effort empty"
        )
    return None


def check_finite(cmd: TrajectoryCommand, index: int) -> str | None:
    """time_from_start, positions, velocities and accelerations must be finite."""
    point = cmd.points[index]
    if not np.isfinite(point.time_from_start):
        return f"points[{index}].time_from_start = {point.time_from_start} s is not finite"
    for field, values in (
        ("positions", point.positions),
        ("velocities", point.velocities),
        ("accelerations", point.accelerations),
    ):
        for name, value in zip(cmd.joint_names, values):
            if not np.isfinite(value):
                return f"points[{index}].{field}[{name}] = {value} is not finite"
    return None


def check_joint_limits(
    cmd: TrajectoryCommand,
    index: int,
    joint_names_config: Sequence[str],
    q_min: np.ndarray,
    q_max: np.ndarray,
) -> str | None:
    """Positions must lie in [q_min, q_max] (config order, (n,) [rad])."""
    for name, value in zip(cmd.joint_names, cmd.points[index].positions):
        j = list(joint_names_config).index(name)
        lo, hi = float(q_min[j]), float(q_max[j])
        if not lo - LIMIT_SLACK <= value <= hi + LIMIT_SLACK:
            return (
                f"points[{index}].positions[{name}] = {value:.6g} rad is outside the joint limits [{lo:.4f}, {hi:.4f}]"
            )
    return None


def check_velocity_limits(
    cmd: TrajectoryCommand,
    index: int,
    joint_names_config: Sequence[str],
    v_max: np.ndarray,
) -> str | None:
    """Given velocities, and the mean velocity of the segment ending at point `index`, must not exceed v_max.

    The segment from the measured state to point 0 is not checked: upstream lets a first point at time 0
    make the reference jump, which the path tolerance then reports.

    Args:
        v_max: (n,) velocity limits, config order [rad/s].
    """
    config = list(joint_names_config)
    point = cmd.points[index]
    for name, value in zip(cmd.joint_names, point.velocities):
        limit = float(v_max[config.index(name)])
        if abs(value) > limit + LIMIT_SLACK:
            return (f"points[{index}].velocities[{name}] = {value:.6g} rad/s exceeds the velocity limit "
                    f"{limit:.4f} rad/s")
    if index == 0:
        return None
    prev = cmd.points[index - 1]
    dt = point.time_from_start - prev.time_from_start
    for name, q1, q0 in zip(cmd.joint_names, point.positions, prev.positions):
        limit = float(v_max[config.index(name)])
        mean = abs(q1 - q0) / dt
        if mean > limit + LIMIT_SLACK:
            return (f"points[{index - 1}] -> points[{index}] moves {name} at {mean:.6g} rad/s on average, above "
                    f"its velocity limit {limit:.4f} rad/s (make time_from_start longer)")
    return None


def validate_trajectory(
    cmd: TrajectoryCommand,
    *,
    joint_names_config: Sequence[str],
    q_min: np.ndarray,
    q_max: np.ndarray,
    now: float,
    allow_partial: bool = False,
    allow_nonzero_end_velocity: bool = False,
    v_max: np.ndarray | None = None,
) -> str | None:
    """Run every rule in upstream order and return the first reason, or None if valid.

    Args:
        cmd: The command as received.
        joint_names_config: n controller joint names.
        q_min: (n,) lower position limits, config order [rad].
        q_max: (n,) upper position limits, config order [rad].
        now: Current time on the controller's clock [s].
        allow_partial: Upstream ``allow_partial_joints_goal``.
        allow_nonzero_end_velocity: Upstream ``allow_nonzero_velocity_at_trajectory_end``.
        v_max: (n,) velocity limits, config order [rad/s]; None skips the velocity check.
    """
    reason = (
        check_joint_count(cmd, joint_names_config, allow_partial)
        or check_joint_names_present(cmd)
        or check_points_present(cmd)
        or check_joint_names_known(cmd, joint_names_config)
        or check_joint_names_unique(cmd)
        or check_end_velocity(cmd, allow_nonzero_end_velocity)
        or check_end_time(cmd, now)
    )
    if reason:
        return reason
    # Upstream checks time, sizes and effort point by point; ours follow once all pass.
    for i in range(len(cmd.points)):
        reason = check_time_from_start(cmd, i) or check_point_sizes(cmd, i) or check_no_effort(cmd, i)
        if reason:
            return reason
    for i in range(len(cmd.points)):
        reason = check_finite(cmd, i) or check_joint_limits(cmd, i, joint_names_config, q_min, q_max)
        if reason is None and v_max is not None:
            reason = check_velocity_limits(cmd, i, joint_names_config, v_max)
        if reason:
            return reason
    return None


def map_to_config_order(
    cmd: TrajectoryCommand, joint_names_config: Sequence[str], current_positions: np.ndarray
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
    config = list(joint_names_config)
    n, count = len(config), len(cmd.points)
    reason = (
        check_joint_names_known(cmd, config)
        or check_joint_names_unique(cmd)
        or (None if cmd.points else "points is empty")
    )
    if reason is None:
        for i in range(count):
            reason = check_point_sizes(cmd, i)
            if reason:
                break
    if reason:
        raise TrajectoryError(f"cannot map an invalid trajectory: {reason}")
    hold = np.asarray(current_positions, dtype=float)
    if hold.shape != (n,):
        raise TrajectoryError(f"current_positions has shape {hold.shape}, expected ({n},)")

    columns = [config.index(name) for name in cmd.joint_names]
    positions = np.tile(hold, (count, 1))
    velocities = np.zeros((count, n))
    accelerations = np.zeros((count, n))
    has_vel = np.zeros(count, dtype=bool)
    has_acc = np.zeros(count, dtype=bool)
    for k, point in enumerate(cmd.points):
        positions[k, columns] = point.positions
        if point.velocities:
            velocities[k, columns] = point.velocities
            has_vel[k] = True
        if point.accelerations:
            accelerations[k, columns] = point.accelerations
            has_acc[k] = True
    return TrajectoryPoints(
        joint_names=tuple(config),
        times=np.array([p.time_from_start for p in cmd.points]),
        positions=positions,
        velocities=velocities,
        accelerations=accelerations,
        has_velocities=has_vel,
        has_accelerations=has_acc,
        header_stamp=cmd.header_stamp,
    )
