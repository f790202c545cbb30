"""Mapping between ROS messages and the pure core's types. With node.py, the only module that touches messages."""
from __future__ import annotations

from array import array
from collections.abc import Sequence
from dataclasses import dataclass

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


def duration_parts(t: float) -> tuple[int, int]:
    """[s] -> (sec, nanosec) of a builtin_interfaces/Duration, which may be negative: sec rounds down, nanosec is in
    [0, 1e9) (-0.3 s is sec -1, nanosec 700000000)."""
    return divmod(round(t * 1e9), 1_000_000_000)


def sec_to_duration(t: float) -> Duration:
    """[s] -> builtin_interfaces/Duration (negative allowed)."""
    sec, nanosec = duration_parts(t)
    return Duration(sec=sec, nanosec=nanosec)


@dataclass(frozen=True)
class RobotClock:
    """Simulated time [s] and the stamps on the wire: a stamp is `origin_ns` plus the simulated time.

    The real driver stamps with the system clock. Running in real time, ur_sim's origin is the wall clock at start,
    so its stamps read as the driver's do (a tf lookup at the client's now finds them); otherwise 0, and clients use
    /clock (use_sim_time). A zero stamp stays zero both ways: on the wire it means "now" / "no end".
    """

    origin_ns: int = 0

    def parts(self, t: float) -> tuple[int, int]:
        """Simulated time `t` [s] -> (sec, nanosec) of its stamp."""
        return divmod(self.origin_ns + max(0, round(t * 1e9)), 1_000_000_000)

    def stamp(self, t: float) -> Time:
        """Simulated time `t` [s] -> its builtin_interfaces/Time."""
        sec, nanosec = self.parts(t)
        return Time(sec=sec, nanosec=nanosec)

    def sim_seconds(self, stamp: float) -> float:
        """A stamp in seconds, as read from a message -> simulated time [s] (0.0 stays 0.0; one before the origin is
        negative, in the past)."""
        return stamp - self.origin_ns * 1e-9 if stamp != 0.0 else 0.0

    def sim_time(self, stamp: Time) -> float:
        """builtin_interfaces/Time -> simulated time [s], exactly to the nanosecond (zero stays 0.0)."""
        ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        return (ns - self.origin_ns) * 1e-9 if ns else 0.0


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
