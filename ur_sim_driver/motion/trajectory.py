"""Sampling a validated trajectory the way ros2_controllers' JTC does (Jazzy).

Rules reproduced from ``joint_trajectory_controller/src/trajectory.cpp``:

* Before the first point's time, a segment runs from the measured start state (taken at
  ``state_time``) to point 0. If the first point's time is not after ``state_time``
  (e.g. ``time_from_start`` 0 and no header stamp), that segment is skipped and the
  reference jumps to point 0, as upstream.
* Between points k and k+1 the degree depends on what both ends carry: positions only
  -> linear, + velocities -> cubic Hermite, + accelerations -> quintic.
* From the last point's time on, the reference holds the last point; ``ended`` is True.

Time is explicit: the caller passes trajectory time, already advanced with the speed
scaling factor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.motion.trajectory_types import TrajectoryPoints


class TrajectorySample(NamedTuple):
    """The reference at one time.

    Attributes:
        positions: (n,) [rad].
        velocities: (n,) [rad/s].
        accelerations: (n,) [rad/s^2].
        segment_index: Index of the point the reference moves towards: 0 while in the
            segment from the start state, k between points k-1 and k, N-1 once ended.
        ended: True once t >= start_time + last time_from_start.
    """

    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    segment_index: int
    ended: bool


def interpolate(
    p0: np.ndarray,
    v0: np.ndarray | None,
    a0: np.ndarray | None,
    p1: np.ndarray,
    v1: np.ndarray | None,
    a1: np.ndarray | None,
    duration: float,
    s: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Polynomial between two states, evaluated s seconds after the first.

    The degree follows what is given: no velocities -> linear; velocities -> cubic;
    velocities and accelerations -> quintic. Accelerations without velocities fall
    back to linear (upstream outputs zeros in that case, a bug we do not copy).

    Args:
        p0, p1: (n,) positions at both ends [rad].
        v0, v1: (n,) velocities [rad/s] or None.
        a0, a1: (n,) accelerations [rad/s^2] or None.
        duration: Segment length T > 0 [s].
        s: Time into the segment [s], clamped to [0, T].

    Returns:
        positions, velocities, accelerations: (n,) each.
    """
    s = min(max(s, 0.0), duration)
    dp = p1 - p0
    if v0 is None or v1 is None:
        rate = dp / duration
        return p0 + rate * s, rate.copy(), np.zeros_like(p0)
    if a0 is None or a1 is None:
        # Hermite cubic: matches p and v at both ends.
        c2 = (3.0 * dp - (2.0 * v0 + v1) * duration) / duration**2
        c3 = (-2.0 * dp + (v0 + v1) * duration) / duration**3
        coefficients = [p0, v0, c2, c3]
    else:
        # Quintic: matches p, v and a at both ends.
        T = duration
        c3 = (20.0 * dp - (8.0 * v1 + 12.0 * v0) * T - (3.0 * a0 - a1) * T**2) / (2.0 * T**3)
        c4 = (-30.0 * dp + (14.0 * v1 + 16.0 * v0) * T + (3.0 * a0 - 2.0 * a1) * T**2) / (2.0 * T**4)
        c5 = (12.0 * dp - 6.0 * (v1 + v0) * T + (a1 - a0) * T**2) / (2.0 * T**5)
        coefficients = [p0, v0, 0.5 * a0, c3, c4, c5]
    q = np.zeros_like(p0)
    qd = np.zeros_like(p0)
    qdd = np.zeros_like(p0)
    for power, c in enumerate(coefficients):
        q = q + c * s**power
        if power >= 1:
            qd = qd + power * c * s ** (power - 1)
        if power >= 2:
            qdd = qdd + power * (power - 1) * c * s ** (power - 2)
    return q, qd, qdd


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A trajectory being executed: the points plus the state it started from.

    Attributes:
        points: Validated trajectory in controller joint order.
        start_time: Time at which time_from_start counts from [s] (header stamp, or
            the time of the first sample when the stamp is 0).
        start_positions: (n,) measured positions at ``state_time`` [rad].
        start_velocities: (n,) measured velocities [rad/s], or None if not measured.
        start_accelerations: (n,) measured accelerations [rad/s^2], or None.
        state_time: Time the start state was measured [s]; defaults to ``start_time``.
    """

    points: TrajectoryPoints
    start_time: float
    start_positions: np.ndarray
    start_velocities: np.ndarray | None = None
    start_accelerations: np.ndarray | None = None
    state_time: float | None = None

    def __post_init__(self) -> None:
        n = len(self.points.joint_names)
        for name in ("start_positions", "start_velocities", "start_accelerations"):
            value = getattr(self, name)
            if value is None:
                continue
            array = np.array(value, dtype=float)
            if array.shape != (n,):
                raise TrajectoryError(f"{name} has shape {array.shape}, expected ({n},)")
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        if self.start_positions is None:
            raise TrajectoryError("start_positions is required")
        if self.state_time is None:
            object.__setattr__(self, "state_time", float(self.start_time))

    @classmethod
    def start(
        cls,
        points: TrajectoryPoints,
        now: float,
        positions: np.ndarray,
        velocities: np.ndarray | None = None,
        accelerations: np.ndarray | None = None,
    ) -> Trajectory:
        """Start a trajectory at its header stamp, or at ``now`` [s] if the stamp is 0."""
        start_time = points.header_stamp if points.header_stamp != 0.0 else now
        return cls(points, start_time, positions, velocities, accelerations, now)

    @property
    def end_time(self) -> float:
        """Absolute time of the last point [s]."""
        return self.start_time + self.points.duration

    def sample(self, t: float) -> TrajectorySample:
        """The reference at absolute (trajectory) time t [s]."""
        pts = self.points
        times = self.start_time + pts.times
        last = len(times) - 1
        if t < self.state_time:
            # Upstream gives no sample before the start state; holding it is the same.
            zero = np.zeros_like(self.start_positions)
            return TrajectorySample(self.start_positions.copy(), zero, zero.copy(), 0, False)
        if t >= times[last]:
            # Hold the last position at rest: upstream repeats the point's own velocity
            # and acceleration, which contradicts holding still when they are non-zero.
            zero = np.zeros_like(self.start_positions)
            return TrajectorySample(pts.positions[last].copy(), zero, zero.copy(), last, True)
        if t < times[0]:
            return self._sample_first_segment(t, times[0])
        k = int(np.searchsorted(times, t, side="right"))  # times[k-1] <= t < times[k]
        q, qd, qdd = interpolate(
            pts.positions[k - 1],
            pts.velocities[k - 1] if pts.has_velocities[k - 1] else None,
            pts.accelerations[k - 1] if pts.has_accelerations[k - 1] else None,
            pts.positions[k],
            pts.velocities[k] if pts.has_velocities[k] else None,
            pts.accelerations[k] if pts.has_accelerations[k] else None,
            float(times[k] - times[k - 1]),
            float(t - times[k - 1]),
        )
        return TrajectorySample(q, qd, qdd, k, False)

    def _sample_first_segment(self, t: float, first_time: float) -> TrajectorySample:
        pts = self.points
        zero = np.zeros_like(self.start_positions)
        # The start state takes the degree of point 0: missing measured derivatives
        # count as zero (upstream fix for ros2_controllers issue #2015; before it, a
        # robot without acceleration state, like the UR, got a cubic first segment).
        v0 = v1 = a0 = a1 = None
        if pts.has_velocities[0]:
            v0 = self.start_velocities if self.start_velocities is not None else zero
            v1 = pts.velocities[0]
        if pts.has_accelerations[0]:
            a0 = self.start_accelerations if self.start_accelerations is not None else zero
            a1 = pts.accelerations[0]
        q, qd, qdd = interpolate(
            self.start_positions,
            v0,
            a0,
            pts.positions[0],
            v1,
            a1,
            float(first_time - self.state_time),
            float(t - self.state_time),
        )
        return TrajectorySample(q, qd, qdd, 0, False)
