"""Trajectory passthrough without ROS: what the UR robot does with a whole trajectory, and how upstream's
passthrough_trajectory_controller judges the end.

Facts from ``ur_controllers/passthrough_trajectory_controller.cpp`` and the driver's hardware interface (jazzy);
the code is ours:

* A goal must give positions for every joint of the robot; velocities and accelerations are all or nothing,
  in every point alike. ``goal_tolerance``, when given, names every joint and only the controller's joints.
  A goal is refused while another one runs (no preemption).
* The robot interpolates the points itself (the hardware sends them as spline points): quintic where positions,
  velocities and accelerations are given, cubic with velocities, and with positions only a cubic through zero
  velocities, so that the robot comes to rest at every point. (Upstream passes accelerations given without
  velocities as if they were velocities; ur_sim treats such points as positions only.) Segment durations are
  the differences of ``time_from_start``; the first segment starts from where the robot is.
* The robot's own speed scaling (speed slider, its slowdowns) stretches the motion; the controller counts
  elapsed time as period x that factor.
* When the robot reports the end: position (and velocity, where the last point has velocities) against the
  goal tolerance, with no defaults (an empty ``goal_tolerance`` always passes; a tolerance of 0 is exact), then,
  where ``goal_time_tolerance`` > 0, elapsed time against the last point's time plus it. Either failing ends
  the goal aborted with GOAL_TOLERANCE_VIOLATED.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.command_arrays import CommandArrays
from ur_sim_driver.motion.trajectory_types import ToleranceSpec, TrajectoryPoints

# Upstream's words.
INACTIVE = "Can't accept new trajectories. Controller is not running."
BUSY = "Can't accept new trajectory. A trajectory is already executing."
NOT_WITHIN_TOLERANCE = 'Robot not within tolerances at end of trajectory.'
DEACTIVATED = 'Aborting current goal, since the controller is being deactivated.'


@dataclass(frozen=True, eq=False)
class PassthroughTolerances:
    """One goal's end criteria, in controller joint order.

    Attributes:
        position: (n,) [rad], or None when the goal gave no goal_tolerance (nothing is checked then).
        velocity: (n,) [rad/s], or None likewise.
        goal_time: goal_time_tolerance [s]; <= 0: elapsed time is not checked.
    """

    position: np.ndarray | None
    velocity: np.ndarray | None
    goal_time: float


def check_goal(cmd: CommandArrays, joints: Sequence[str], tolerance_names: Sequence[str]) -> str | None:
    """The passthrough controller's own rules for a goal (besides the common validation), or None."""
    n = len(joints)
    sizes = cmd.sizes
    for k in range(cmd.count):
        if sizes[k, 0] != n:
            return (f'points[{k}].positions has {sizes[k, 0]} values: all trajectory points must have positions '
                    f'for all {n} joints of the robot')
    for field, column in (('velocities', 1), ('accelerations', 2)):
        if cmd.count and np.any(sizes[:, column] != sizes[0, column]):
            k = int(np.flatnonzero(sizes[:, column] != sizes[0, column])[0])
            return (f'points[{k}].{field} has {sizes[k, column]} values but points[0] has {sizes[0, column]}: '
                    f'all points must have {field} for all {n} joints, or none')
    if tolerance_names:
        for name in tolerance_names:
            if name not in joints:
                return f"Tolerance for joint '{name}' given. This joint is not known to this controller."
        if len(tolerance_names) != n:
            return f'Tolerances for {len(tolerance_names)} joints given. This controller knows {n} joints.'
    return None


def tolerances_of(specs: Sequence[ToleranceSpec], joints: Sequence[str], goal_time: float) -> PassthroughTolerances:
    """The goal's tolerances in controller order (specs already checked with :func:`check_goal`)."""
    if not specs:
        return PassthroughTolerances(None, None, goal_time)
    by_name = {s.name: s for s in specs}
    return PassthroughTolerances(np.array([by_name[j].position for j in joints]),
                                 np.array([by_name[j].velocity for j in joints]), goal_time)


def robot_points(points: TrajectoryPoints) -> TrajectoryPoints:
    """The points as the robot interpolates them: without velocities, each point is reached at rest (zero
    velocities: a cubic through them). The robot starts when it has the trajectory (header.stamp is not used)."""
    p = points
    if bool(p.has_velocities.all()):
        accelerations = p.accelerations if bool(p.has_accelerations.all()) else np.zeros_like(p.positions)
        return TrajectoryPoints(p.joint_names, p.times, p.positions, p.velocities, accelerations,
                                p.has_velocities, p.has_accelerations & bool(p.has_accelerations.all()), 0.0)
    zero = np.zeros_like(p.positions)
    return TrajectoryPoints(p.joint_names, p.times, p.positions, zero, zero.copy(), np.ones_like(p.has_velocities),
                            np.zeros_like(p.has_accelerations), 0.0)


def judge_end(q: np.ndarray, qd: np.ndarray, final: np.ndarray, final_velocity: np.ndarray | None,
              tol: PassthroughTolerances, elapsed: float, duration: float) -> tuple[int, str]:
    """(result code, error_string) when the robot reports the end of the trajectory.

    Args:
        q, qd: (n,) measured state [rad], [rad/s].
        final: (n,) the last point's positions [rad]; final_velocity its velocities, or None when not given.
        tol: the goal's tolerances.
        elapsed: trajectory time counted by the controller (scaled) [s].
        duration: the last point's time_from_start [s].
    """
    if tol.position is not None:
        bad = np.abs(q - final) > tol.position
        if final_velocity is not None and tol.velocity is not None:
            bad |= np.abs(qd - final_velocity) > tol.velocity
        if bad.any():
            return result_codes.GOAL_TOLERANCE_VIOLATED, NOT_WITHIN_TOLERANCE
    if tol.goal_time > 0.0 and elapsed > duration + tol.goal_time:
        return (result_codes.GOAL_TOLERANCE_VIOLATED,
                f'Goal not reached within time tolerance. Missed goal time by '
                f'{elapsed - duration - tol.goal_time:.6f} seconds.')
    return (result_codes.SUCCESSFUL, f'Trajectory executed successfully in {elapsed:.6f} (scaled) seconds! '
            'The real time needed for execution could be longer.')
