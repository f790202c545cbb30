"""Plain data types of the trajectory controller core (no ROS types).

Two stages of a trajectory live here:

* :class:`TrajectoryCommand` mirrors a ``trajectory_msgs/JointTrajectory`` as received:
  joint names in the sender's order and per-point value tuples that may be empty or
  ragged. Validation (``validation.py``) reports on it, so nothing is rejected here.
* :class:`TrajectoryPoints` is a validated command in the controller's joint order, as
  numpy arrays, ready for interpolation (``trajectory.py``).

Tolerance types mirror ``control_msgs/JointTolerance`` (:class:`ToleranceSpec`) and the
resolved per-joint tolerances the controller checks (:class:`JointTolerances`,
:class:`SegmentTolerances`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np


def _floats(values: Iterable[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


def _frozen(array: np.ndarray) -> np.ndarray:
    # Frozen dataclasses only stop attribute assignment; this stops in-place edits too.
    array = np.array(array, dtype=float)
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class CommandPoint:
    """One ``JointTrajectoryPoint`` as received; empty tuples mean "not given".

    Attributes:
        time_from_start: Time of the point relative to the trajectory start [s].
        positions: One value per joint name [rad] (may have a wrong size before validation).
        velocities: Empty or one value per joint name [rad/s].
        accelerations: Empty or one value per joint name [rad/s^2].
        effort: Empty or one value per joint name [N m] (rejected by validation).
    """

    time_from_start: float
    positions: tuple[float, ...]
    velocities: tuple[float, ...] = ()
    accelerations: tuple[float, ...] = ()
    effort: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        # Accept lists and arrays from callers but store hashable, immutable tuples.
        object.__setattr__(self, "time_from_start", float(self.time_from_start))
        for name in ("positions", "velocities", "accelerations", "effort"):
            object.__setattr__(self, name, _floats(getattr(self, name)))


@dataclass(frozen=True)
class TrajectoryCommand:
    """A ``JointTrajectory`` message as received, before validation.

    Attributes:
        joint_names: Joint names in the sender's order (any order, possibly partial).
        points: The trajectory points, in message order.
        header_stamp: ``header.stamp`` [s]; 0.0 means "start when received".
    """

    joint_names: tuple[str, ...]
    points: tuple[CommandPoint, ...]
    header_stamp: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint_names", tuple(str(n) for n in self.joint_names))
        object.__setattr__(self, "points", tuple(self.points))
        object.__setattr__(self, "header_stamp", float(self.header_stamp))

    @classmethod
    def from_arrays(
        cls,
        joint_names: Sequence[str],
        times: Sequence[float],
        positions: Sequence[Sequence[float]],
        velocities: Sequence[Sequence[float]] | None = None,
        accelerations: Sequence[Sequence[float]] | None = None,
        header_stamp: float = 0.0,
    ) -> TrajectoryCommand:
        """Build a command from rectangular data.

        Args:
            joint_names: n joint names.
            times: (N,) time_from_start of each point [s].
            positions: (N, n) positions [rad].
            velocities: (N, n) velocities [rad/s], or None for none given.
            accelerations: (N, n) accelerations [rad/s^2], or None for none given.
            header_stamp: Trajectory start [s]; 0.0 = start now.
        """
        count = len(times)
        vel = velocities if velocities is not None else [()] * count
        acc = accelerations if accelerations is not None else [()] * count
        points = tuple(CommandPoint(t, p, v, a) for t, p, v, a in zip(times, positions, vel, acc))
        return cls(tuple(joint_names), points, header_stamp)


@dataclass(frozen=True, eq=False)
class TrajectoryPoints:
    """A validated trajectory in the controller's joint order.

    Velocities and accelerations are per point: upstream lets each point carry them or
    not, and picks the interpolation degree per segment from both ends.

    Attributes:
        joint_names: n joint names, controller order.
        times: (N,) strictly increasing time_from_start [s].
        positions: (N, n) [rad].
        velocities: (N, n) [rad/s]; rows without ``has_velocities`` are zero.
        accelerations: (N, n) [rad/s^2]; rows without ``has_accelerations`` are zero.
        has_velocities: (N,) bool, whether point k carried velocities.
        has_accelerations: (N,) bool, whether point k carried accelerations.
        header_stamp: Trajectory start [s]; 0.0 = start now.
    """

    joint_names: tuple[str, ...]
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    has_velocities: np.ndarray
    has_accelerations: np.ndarray
    header_stamp: float = 0.0

    def __post_init__(self) -> None:
        for name in ("times", "positions", "velocities", "accelerations"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        for name in ("has_velocities", "has_accelerations"):
            flags = np.array(getattr(self, name), dtype=bool)
            flags.setflags(write=False)
            object.__setattr__(self, name, flags)
        count, n = len(self.times), len(self.joint_names)
        for name in ("positions", "velocities", "accelerations"):
            if getattr(self, name).shape != (count, n):
                raise ValueError(f"{name} has shape {getattr(self, name).shape}, expected ({count}, {n})")
        if count == 0:
            raise ValueError("a trajectory needs at least one point")

    @property
    def duration(self) -> float:
        """time_from_start of the last point [s]."""
        return float(self.times[-1])


@dataclass(frozen=True)
class ToleranceSpec:
    """One ``control_msgs/JointTolerance`` entry of a goal.

    Values: > 0 overrides the default, 0 keeps the default, -1 removes the check.

    Attributes:
        name: Joint name.
        position: [rad].
        velocity: [rad/s].
        acceleration: [rad/s^2].
    """

    name: str
    position: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0


@dataclass(frozen=True, eq=False)
class JointTolerances:
    """Resolved per-joint state tolerances; a value <= 0 means "not checked".

    Attributes:
        position: (n,) [rad].
        velocity: (n,) [rad/s].
        acceleration: (n,) [rad/s^2].
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray

    def __post_init__(self) -> None:
        for name in ("position", "velocity", "acceleration"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        shapes = {self.position.shape, self.velocity.shape, self.acceleration.shape}
        if len(shapes) != 1 or self.position.ndim != 1:
            raise ValueError(f"tolerance arrays must share one (n,) shape, got {shapes}")

    @classmethod
    def unchecked(cls, n: int) -> JointTolerances:
        """Tolerances that check nothing, for n joints."""
        return cls(np.zeros(n), np.zeros(n), np.zeros(n))


@dataclass(frozen=True)
class SegmentTolerances:
    """Everything the controller checks while executing one goal.

    Attributes:
        path: Checked while the trajectory runs (upstream ``state_tolerance``).
        goal: Checked once the last point's time has passed (``goal_state_tolerance``);
            its velocity defaults to ``stopped_velocity_tolerance``.
        goal_time: Time after the end allowed to reach ``goal`` [s]; 0 = no limit
            (upstream waits until the goal is met, cancelled or replaced).
    """

    path: JointTolerances
    goal: JointTolerances
    goal_time: float = 0.0
