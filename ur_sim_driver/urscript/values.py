"""URScript's values: numbers, booleans, strings, lists and the pose ``p[x, y, z, rx, ry, rz]`` (position [m] and
rotation vector [rad] in the robot's base frame), with the pose functions, how textmsg shows a value, what counts
as true, and the Request a program yields when it needs robot time."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ur_sim_driver.errors import ScriptError


@dataclass(frozen=True)
class Pose:
    """A URScript pose: position (3,) [m] and rotation vector (3,) [rad]."""

    values: tuple[float, float, float, float, float, float]

    @staticmethod
    def from_matrix(t: np.ndarray) -> Pose:
        rv = Rotation.from_matrix(t[:3, :3]).as_rotvec()
        return Pose(tuple(float(v) for v in (*t[:3, 3], *rv)))

    def matrix(self) -> np.ndarray:
        """The homogeneous transform (4, 4)."""
        t = np.eye(4)
        t[:3, :3] = Rotation.from_rotvec(self.values[3:]).as_matrix()
        t[:3, 3] = self.values[:3]
        return t

    def __str__(self) -> str:  # as textmsg shows a pose
        return 'p[' + ', '.join(f'{v:.6g}' for v in self.values) + ']'


def pose_trans(p_from: Pose, p_from_to: Pose) -> Pose:
    """`p_from_to` seen from `p_from`, in the base frame: p_from * p_from_to."""
    return Pose.from_matrix(p_from.matrix() @ p_from_to.matrix())


def pose_inv(p: Pose) -> Pose:
    return Pose.from_matrix(np.linalg.inv(p.matrix()))


def pose_add(p_1: Pose, p_2: Pose) -> Pose:
    """Positions added, rotations composed (p_2's after p_1's), as URScript's pose_add."""
    r = Rotation.from_rotvec(p_2.values[3:]) * Rotation.from_rotvec(p_1.values[3:])
    position = np.add(p_1.values[:3], p_2.values[:3])
    return Pose(tuple(float(v) for v in (*position, *r.as_rotvec())))


def pose_dist(p_from: Pose, p_to: Pose) -> float:
    """[m] the distance between the two positions."""
    return float(np.linalg.norm(np.subtract(p_from.values[:3], p_to.values[:3])))


def interpolate_pose(p_from: Pose, p_to: Pose, alpha: float) -> Pose:
    """The pose a fraction `alpha` of the way from `p_from` to `p_to` (0: p_from, 1: p_to): the position on the
    line, the orientation on the shortest rotation between the two (outside [0, 1] both go on beyond)."""
    r0 = Rotation.from_rotvec(p_from.values[3:])
    turn = (Rotation.from_rotvec(p_to.values[3:]) * r0.inv()).as_rotvec()
    position = np.add(p_from.values[:3], alpha * np.subtract(p_to.values[:3], p_from.values[:3]))
    r = Rotation.from_rotvec(alpha * turn) * r0
    return Pose(tuple(float(v) for v in (*position, *r.as_rotvec())))


def show(value) -> str:
    """A value as textmsg writes it."""
    if isinstance(value, bool):
        return 'True' if value else 'False'
    if isinstance(value, list):
        return '[' + ', '.join(show(v) for v in value) + ']'
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)


@dataclass(frozen=True)
class ThreadHandle:
    """What ``run name()`` returns: the thread's number (from 1; never equal to a number, so ``h != 0`` holds, as
    programs test it) and its name."""

    number: int
    name: str

    def __str__(self) -> str:  # as textmsg shows it
        return f'Thread_{self.name}_{self.number}'


@dataclass(frozen=True)
class Request:
    """What a thread waits for: `kind` ('move', 'sleep', 'sync', 'join' or 'wait') and its arguments (a move's: its
    name and the URScript arguments, resolved; a join's: the condition; a wait's: a poll that returns PENDING until
    it returns the call's value)."""

    kind: str
    args: tuple = ()


REQUIRED = object()  # a builtin argument without a default
PENDING = object()  # a poll's answer while what it waits for has not come


def is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def truth(v) -> bool:
    if isinstance(v, bool):
        return v
    if is_number(v):
        return v != 0
    raise ScriptError(f'a condition is a boolean or a number; got {show(v)}')


def numbers(name: str, value, n: int = 6) -> list[float]:
    """`value` as `n` floats (a list or a pose); ScriptError naming `name` otherwise."""
    items = value.values if isinstance(value, Pose) else value
    if not isinstance(items, (list, tuple)) or len(items) != n or not all(is_number(v) for v in items):
        raise ScriptError(f'{name} is a list of {n} numbers; got {show(value)}')
    return [float(v) for v in items]


def pose_argument(name: str, value) -> Pose:
    """`value` if it is a pose; ScriptError naming `name` otherwise."""
    if not isinstance(value, Pose):
        raise ScriptError(f'{name} is a pose p[x, y, z, rx, ry, rz]; got {show(value)}')
    return value
