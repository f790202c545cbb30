"""Mapping between ROS messages and the pure core's types. With node.py, the only module that touches messages."""
from __future__ import annotations

from array import array
from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Duration, Time
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ur_sim_driver.motion.trajectory_types import CommandPoint, ToleranceSpec, TrajectoryCommand


def duration_to_sec(d: Duration) -> float:
    """builtin_interfaces/Duration -> [s]."""
    return d.sec + d.nanosec * 1e-9


def time_to_sec(t: Time) -> float:
    """builtin_interfaces/Time -> [s]."""
    return t.sec + t.nanosec * 1e-9


def sec_to_time(t: float) -> Time:
    """[s] -> builtin_interfaces/Time (non-negative)."""
    sec, nanosec = time_parts(t)
    return Time(sec=sec, nanosec=nanosec)


def time_parts(t: float) -> tuple[int, int]:
    """[s] -> (sec, nanosec) of a builtin_interfaces/Time (non-negative)."""
    return divmod(max(0, round(t * 1e9)), 1_000_000_000)


def duration_parts(t: float) -> tuple[int, int]:
    """[s] -> (sec, nanosec) of a builtin_interfaces/Duration, which may be negative: sec rounds down, nanosec is in
    [0, 1e9) (-0.3 s is sec -1, nanosec 700000000)."""
    return divmod(round(t * 1e9), 1_000_000_000)


def sec_to_duration(t: float) -> Duration:
    """[s] -> builtin_interfaces/Duration (negative allowed)."""
    sec, nanosec = duration_parts(t)
    return Duration(sec=sec, nanosec=nanosec)


def trajectory_command(msg: JointTrajectory) -> TrajectoryCommand:
    """A JointTrajectory as received, for validation (ragged arrays are kept as they are)."""
    points = tuple(
        CommandPoint(duration_to_sec(p.time_from_start), tuple(p.positions), tuple(p.velocities),
                     tuple(p.accelerations), tuple(p.effort))
        for p in msg.points)
    return TrajectoryCommand(tuple(msg.joint_names), points, time_to_sec(msg.header.stamp))


def tolerance_specs(tolerances: Sequence) -> tuple[ToleranceSpec, ...]:
    """control_msgs/JointTolerance[] -> ToleranceSpec tuple."""
    return tuple(ToleranceSpec(t.name, t.position, t.velocity, t.acceleration) for t in tolerances)


def trajectory_point(q: np.ndarray | None = None, qd: np.ndarray | None = None, qdd: np.ndarray | None = None,
                     effort: np.ndarray | None = None) -> JointTrajectoryPoint:
    """A JointTrajectoryPoint with the arrays that are given."""
    p = JointTrajectoryPoint()
    fill_point(p, q, qd, qdd, effort)
    return p


def float_array(x: np.ndarray) -> array:
    """A float64 array in the form message setters take without per-element checks."""
    return array('d', np.ascontiguousarray(x, dtype=np.float64).tobytes())


def fill_point(p: JointTrajectoryPoint, q: np.ndarray | None = None, qd: np.ndarray | None = None,
               qdd: np.ndarray | None = None, effort: np.ndarray | None = None) -> None:
    """Overwrite the given arrays of an existing point (reused messages keep the hot loop cheap)."""
    if q is not None:
        p.positions = float_array(q)
    if qd is not None:
        p.velocities = float_array(qd)
    if qdd is not None:
        p.accelerations = float_array(qdd)
    if effort is not None:
        p.effort = float_array(effort)
