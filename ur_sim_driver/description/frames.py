"""The orientations of the robot's frames at given joint positions, from the kinematic tree the URDF is built from.

What tf2 would answer for a rotation between two frames of the robot (``robot_state_publisher``'s tree): a service
that takes a vector in any frame (set_gravity) turns it into the base frame with :func:`rotation_between`.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur_sim_driver.description.urdf import JointSpec


def _rz(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def frame_rotations(tree: Sequence[JointSpec], q: np.ndarray) -> dict[str, np.ndarray]:
    """Every frame of `tree` (parents before children) -> its rotation (3, 3) in the tree's root frame, with the
    revolute joints at `q` (n,) [rad]."""
    rotations = {tree[0].parent: np.eye(3)}
    for joint in tree:
        r = rotations[joint.parent] @ joint.origin.matrix()[:3, :3]
        rotations[joint.child] = r @ _rz(float(q[joint.index])) if joint.index is not None else r
    return rotations


def frame_poses(tree: Sequence[JointSpec], q: np.ndarray) -> dict[str, np.ndarray]:
    """Every frame of `tree` -> its pose (4, 4) in the tree's root frame, with the revolute joints at `q` [rad]."""
    poses = {tree[0].parent: np.eye(4)}
    for joint in tree:
        t = poses[joint.parent] @ joint.origin.matrix()
        if joint.index is not None:
            t = t.copy()
            t[:3, :3] = t[:3, :3] @ _rz(float(q[joint.index]))
        poses[joint.child] = t
    return poses


def pose_between(poses: dict[str, np.ndarray], target: str, source: str) -> np.ndarray:
    """(4, 4) pose of `source` in `target` (tf2's lookupTransform(target, source)).

    Raises:
        KeyError: a frame the tree does not have (the message names it and lists the frames).
    """
    for frame in (target, source):
        if frame not in poses:
            raise KeyError(f'frame {frame!r} does not exist; frames: {", ".join(sorted(poses))}')
    return np.linalg.inv(poses[target]) @ poses[source]


def rotation_between(rotations: dict[str, np.ndarray], target: str, source: str) -> np.ndarray:
    """(3, 3) rotation taking vectors in `source` to `target` (tf2's lookupTransform(target, source) rotation).

    Raises:
        KeyError: a frame the tree does not have (the message names it and lists the frames).
    """
    for frame in (target, source):
        if frame not in rotations:
            raise KeyError(f'frame {frame!r} does not exist; frames: {", ".join(sorted(rotations))}')
    return rotations[target].T @ rotations[source]
