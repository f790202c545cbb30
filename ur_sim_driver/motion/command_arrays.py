"""A received trajectory as flat numpy arrays: the form validation and mapping work on, fast for any length.

A ``trajectory_msgs/JointTrajectory`` may be ragged (each point's arrays have their own length), so the values
are kept flat, point after point, with a (N, 4) table of lengths. Building this from 100,000 points takes
tens of milliseconds (:func:`from_points`, :func:`cdr.parse_joint_trajectory`), where a Python object per
point took seconds; once the lengths are known to be rectangular, :meth:`CommandArrays.block` gives (N, n)
views without copying.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from operator import attrgetter

import numpy as np

from ur_sim_driver.motion.trajectory_types import TrajectoryCommand

FIELDS = ('positions', 'velocities', 'accelerations', 'effort')


@dataclass(frozen=True, eq=False)
class CommandArrays:
    """A JointTrajectory as received.

    Attributes:
        joint_names: n names in the sender's order.
        header_stamp: header.stamp [s]; 0 = start on receipt.
        times: (N,) time_from_start [s].
        sizes: (N, 4) int, lengths of positions, velocities, accelerations and effort of each point.
        values: the four fields' values, each flat (sum of its column of `sizes`,) float64.
    """

    joint_names: tuple[str, ...]
    header_stamp: float
    times: np.ndarray
    sizes: np.ndarray
    values: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

    @property
    def count(self) -> int:
        """Number of points N."""
        return len(self.times)

    def offsets(self, field: int) -> np.ndarray:
        """(N + 1,) start of each point's values of `field` (0..3) in ``values[field]``."""
        out = np.zeros(self.count + 1, dtype=np.int64)
        np.cumsum(self.sizes[:, field], out=out[1:])
        return out

    def point_values(self, field: int, index: int) -> np.ndarray:
        """Values of `field` (0..3) at point `index` (1-D, as received)."""
        start = int(self.sizes[:index, field].sum())
        return self.values[field][start:start + int(self.sizes[index, field])]

    def block(self, field: int) -> tuple[np.ndarray, np.ndarray]:
        """(N, n) values of `field` (rows of points without it are zero) and (N,) bool "given" flags.

        Valid only once every point has 0 or n values of `field` (validation checks this first).
        """
        n = len(self.joint_names)
        given = self.sizes[:, field] == n
        flat = self.values[field]
        if given.all():
            return flat.reshape(self.count, n), given
        out = np.zeros((self.count, n))
        out[given] = flat.reshape(-1, n)
        return out, given


def from_points(joint_names: Sequence[str], header_stamp: float, points: Sequence) -> CommandArrays:
    """From JointTrajectoryPoint-like objects (``positions``..``effort`` as float sequences, ``time_from_start``
    with ``sec`` and ``nanosec``): a few C-level passes over the points (about 0.2 s for 100,000 here)."""
    count = len(points)
    sizes = np.zeros((count, 4), dtype=np.int64)
    values = []
    for f, name in enumerate(FIELDS):
        arrays = list(map(attrgetter(name), points))
        sizes[:, f] = np.fromiter(map(len, arrays), dtype=np.int64, count=count)
        values.append(_join(arrays))
    stamps = list(map(attrgetter('time_from_start'), points))
    sec = np.fromiter(map(attrgetter('sec'), stamps), dtype=np.int64, count=count)
    nanosec = np.fromiter(map(attrgetter('nanosec'), stamps), dtype=np.int64, count=count)
    return CommandArrays(tuple(str(n) for n in joint_names), float(header_stamp), sec + nanosec * 1e-9, sizes,
                         tuple(values))


def from_command(cmd: TrajectoryCommand) -> CommandArrays:
    """From the plain :class:`TrajectoryCommand` (tests and scripts build those)."""
    points = cmd.points
    sizes = np.array([(len(p.positions), len(p.velocities), len(p.accelerations), len(p.effort))
                      for p in points], dtype=np.int64).reshape(-1, 4)
    times = np.array([p.time_from_start for p in points], dtype=float)
    values = tuple(np.array([x for p in points for x in getattr(p, f)], dtype=float) for f in FIELDS)
    return CommandArrays(cmd.joint_names, cmd.header_stamp, times, sizes, values)


def _join(arrays: list) -> np.ndarray:
    # rclpy gives array('d') per field; their buffers join in one C call. Other sequences go through numpy.
    try:
        return np.frombuffer(b''.join(arrays), dtype=np.float64).copy()
    except TypeError:
        return np.array([x for a in arrays for x in a], dtype=float)
