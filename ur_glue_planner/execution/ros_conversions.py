"""Messages for ur_glue_planner's ROS boundary (client.py, node.py): arrays in, messages out."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Duration, Time
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint


def duration(t: float) -> Duration:
    """[s] -> builtin_interfaces/Duration."""
    ns = round(t * 1e9)
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def stamp(t: float) -> Time:
    """[s] -> builtin_interfaces/Time."""
    ns = max(0, round(t * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def joint_trajectory(names: Sequence[str], times: Sequence[float], q: np.ndarray, qd: np.ndarray | None = None,
                     qdd: np.ndarray | None = None, start_time: float = 0.0) -> JointTrajectory:
    """A JointTrajectory from (N, n) arrays and (N,) times [s]; header stamp `start_time` [s] (0 = on arrival)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    msg = JointTrajectory(joint_names=list(names))
    msg.header.stamp = stamp(start_time)
    for k, t in enumerate(times):
        p = JointTrajectoryPoint(positions=q[k].tolist(), time_from_start=duration(float(t)))
        if qd is not None:
            p.velocities = np.atleast_2d(qd)[k].astype(float).tolist()
        if qdd is not None:
            p.accelerations = np.atleast_2d(qdd)[k].astype(float).tolist()
        msg.points.append(p)
    return msg
