"""Path and goal tolerances of a FollowJointTrajectory goal, as the Jazzy JTC applies them.

Facts from ros2_controllers ``joint_trajectory_controller/tolerances.hpp`` and the
controller's ``update()``:

* Defaults come from the ``constraints`` parameters: per joint ``trajectory`` (path
  position) and ``goal`` (goal position); ``stopped_velocity_tolerance`` becomes the goal
  velocity tolerance of every joint; ``goal_time`` the goal time tolerance.
* A goal's ``path_tolerance``, ``goal_tolerance`` and ``goal_time_tolerance`` values:
  > 0 replaces the default, 0 keeps it, -1 removes the check (0 = unchecked), any
  other negative value is illegal. An unknown joint name or an illegal value makes
  upstream log an error and use the defaults for the whole goal; the goal still runs.
* A tolerance of 0 is not checked; a check fails when |error| > tolerance.
* Path tolerances are checked while the trajectory runs (and on the first sample, even
  if that is already past the end); goal tolerances once the last point's time has
  passed. Outside the goal tolerance, the goal fails with GOAL_TOLERANCE_VIOLATED once
  more than ``goal_time`` has passed since the end; with ``goal_time`` 0 upstream keeps
  waiting (holding the last point) until the goal is met, cancelled or replaced. We do
  the same: a caller wanting a limit sets ``goal_time``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.trajectory_types import JointTolerances, SegmentTolerances, ToleranceSpec

# control_msgs/JointTolerance: -1 erases a tolerance. Upstream matches it within
# std::numeric_limits<float>::epsilon().
ERASE_VALUE = -1.0
_ERASE_EPSILON = float(np.finfo(np.float32).eps)


def default_tolerances(
    joint_names: Sequence[str],
    *,
    trajectory: float | Sequence[float],
    goal: float | Sequence[float],
    stopped_velocity: float,
    goal_time: float,
) -> SegmentTolerances:
    """Defaults from the controller's ``constraints`` parameters.

    Args:
        joint_names: n controller joint names.
        trajectory: Path position tolerance [rad], one for all or (n,).
        goal: Goal position tolerance [rad], one for all or (n,).
        stopped_velocity: ``stopped_velocity_tolerance`` [rad/s], the goal velocity
            tolerance of every joint.
        goal_time: ``goal_time`` [s]; 0 = wait for the goal tolerance without limit.

    Raises:
        ConfigError: A value is negative or a per-joint list has the wrong length.
    """
    n = len(joint_names)

    def per_joint(name: str, value: float | Sequence[float]) -> np.ndarray:
        array = np.asarray(value, dtype=float)
        if array.ndim == 0:
            array = np.full(n, float(array))
        if array.shape != (n,):
            raise ConfigError(f"constraints.{name} has {array.size} values, expected {n}")
        if np.any(array < 0.0) or not np.all(np.isfinite(array)):
            raise ConfigError(f"constraints.{name} = {array.tolist()} must be finite and >= 0")
        return array

    if not (np.isfinite(stopped_velocity) and stopped_velocity >= 0.0):
        raise ConfigError(f"constraints.stopped_velocity_tolerance = {stopped_velocity} must be finite and >= 0")
    if not (np.isfinite(goal_time) and goal_time >= 0.0):
        raise ConfigError(f"constraints.goal_time = {goal_time} s must be finite and >= 0")
    zeros = np.zeros(n)
    return SegmentTolerances(
        path=JointTolerances(per_joint("trajectory", trajectory), zeros, zeros),
        goal=JointTolerances(per_joint("goal", goal), np.full(n, float(stopped_velocity)), zeros),
        goal_time=float(goal_time),
    )


def resolve_value(default: float, requested: float) -> float | None:
    """One tolerance: > 0 -> requested, 0 -> default, -1 -> 0 (unchecked), else None."""
    if requested > 0.0:
        return float(requested)
    if abs(requested - ERASE_VALUE) < _ERASE_EPSILON:
        return 0.0
    if requested == 0.0:
        return float(default)
    return None  # other negative values and NaN are illegal


def _apply(
    base: JointTolerances,
    specs: Sequence[ToleranceSpec],
    joint_names: Sequence[str],
    field: str,
) -> tuple[JointTolerances, str | None]:
    arrays = {k: getattr(base, k).copy() for k in ("position", "velocity", "acceleration")}
    for spec in specs:
        if spec.name not in joint_names:
            return base, (
                f"{field}: joint '{spec.name}' is not a controller joint "
                f"(expected names from: {', '.join(joint_names)})"
            )
        j = list(joint_names).index(spec.name)
        for kind, array in arrays.items():
            requested = getattr(spec, kind)
            value = resolve_value(float(getattr(base, kind)[j]), requested)
            if value is None:
                return base, (
                    f"{field}[{spec.name}].{kind} = {requested} is illegal "
                    "(use > 0 to set, 0 for the default, -1 to remove the check)"
                )
            array[j] = value
    return JointTolerances(**arrays), None


def resolve_tolerances(
    defaults: SegmentTolerances,
    joint_names: Sequence[str],
    path_overrides: Sequence[ToleranceSpec] = (),
    goal_overrides: Sequence[ToleranceSpec] = (),
    goal_time_tolerance: float = 0.0,
) -> tuple[SegmentTolerances, str | None]:
    """Tolerances for one goal: the defaults with the goal's overrides applied.

    Args:
        defaults: From :func:`default_tolerances`.
        joint_names: n controller joint names (order of the tolerance arrays).
        path_overrides: The goal's ``path_tolerance`` entries.
        goal_overrides: The goal's ``goal_tolerance`` entries.
        goal_time_tolerance: The goal's ``goal_time_tolerance`` [s].

    Returns:
        (tolerances, reason). When reason is not None (unknown joint, illegal value),
        tolerances are ``defaults`` unchanged, as upstream, which logs the reason and
        runs the goal with its defaults.
    """
    goal_time = resolve_value(defaults.goal_time, goal_time_tolerance)
    if goal_time is None:
        return defaults, (
            f"goal_time_tolerance = {goal_time_tolerance} s is illegal "
            "(use > 0 to set, 0 for the default, -1 to remove the limit)"
        )
    path, reason = _apply(defaults.path, path_overrides, joint_names, "path_tolerance")
    if reason:
        return defaults, reason
    goal, reason = _apply(defaults.goal, goal_overrides, joint_names, "goal_tolerance")
    if reason:
        return defaults, reason
    return SegmentTolerances(path=path, goal=goal, goal_time=goal_time), None


def check_state_tolerance(
    error_pos: np.ndarray,
    error_vel: np.ndarray | None,
    error_acc: np.ndarray | None,
    tol: JointTolerances,
    joint_names: Sequence[str],
    label: str = "state",
) -> str | None:
    """First joint whose error exceeds its tolerance, as a reason; None if all within.

    Args:
        error_pos: (n,) desired - actual position [rad].
        error_vel: (n,) desired - actual velocity [rad/s], or None (not checked).
        error_acc: (n,) desired - actual acceleration [rad/s^2], or None (not checked).
        tol: Tolerances; entries <= 0 are not checked.
        joint_names: n joint names, same order.
        label: Names the check in the reason ("path", "goal").
    """
    for kind, error, limit, unit in (
        ("position", error_pos, tol.position, "rad"),
        ("velocity", error_vel, tol.velocity, "rad/s"),
        ("acceleration", error_acc, tol.acceleration, "rad/s^2"),
    ):
        if error is None:
            continue
        error = np.asarray(error, dtype=float)
        # A non-finite error fails where checked (upstream's |nan| > tol would pass).
        bad = (limit > 0.0) & ~(np.abs(error) <= limit)
        if np.any(bad):
            j = int(np.argmax(bad))
            return (
                f"{label} tolerance violated: {joint_names[j]} {kind} error "
                f"{error[j]:.6g} {unit} exceeds the tolerance {limit[j]:.6g} {unit}"
            )
    return None


def check_path(
    error_pos: np.ndarray,
    error_vel: np.ndarray | None,
    error_acc: np.ndarray | None,
    tolerances: SegmentTolerances,
    joint_names: Sequence[str],
) -> str | None:
    """Path tolerance check (while running, and on the first sample of a goal)."""
    return check_state_tolerance(error_pos, error_vel, error_acc, tolerances.path, joint_names, "path")


def check_goal(
    error_pos: np.ndarray,
    error_vel: np.ndarray | None,
    error_acc: np.ndarray | None,
    tolerances: SegmentTolerances,
    joint_names: Sequence[str],
) -> str | None:
    """Goal tolerance check after the end; velocity uses stopped_velocity by default."""
    return check_state_tolerance(error_pos, error_vel, error_acc, tolerances.goal, joint_names, "goal")


def goal_outcome(time_since_end: float, goal_reason: str | None, goal_time: float) -> int | None:
    """Result code once the trajectory has ended, or None to keep waiting.

    Args:
        time_since_end: t - end time of the last point [s]; negative = still running.
        goal_reason: :func:`check_goal` result at this time.
        goal_time: Resolved goal time tolerance [s]; 0 = no limit (upstream waits).

    Returns:
        SUCCESSFUL once ended within the goal tolerance; GOAL_TOLERANCE_VIOLATED when
        outside it and more than goal_time > 0 has passed; else None.
    """
    if time_since_end < 0.0:
        return None
    if goal_reason is None:
        return result_codes.SUCCESSFUL
    if goal_time > 0.0 and time_since_end > goal_time:
        return result_codes.GOAL_TOLERANCE_VIOLATED
    return None
