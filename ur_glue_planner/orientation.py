"""Rotations in the planner's conventions, all computed by SciPy's ``Rotation`` (the project's one rotation library).

Quaternions are scalar-first ``(w, x, y, z)`` like MATLAB's ``quaternion``/``rotm2quat``, and canonical (w >= 0);
``ur_common.quaternions`` converts them (shared with the simulator). ROS messages order them ``(x, y, z, w)``, so
convert at the ROS boundary only. Every function accepts a leading batch shape, e.g. quaternions (..., 4), matrices
(..., 3, 3).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from ur_common.quaternions import from_rotation, quat_from_matrix, quat_normalize, to_rotation


def rot_x(angle: float) -> np.ndarray:
    """Rotation about x by ``angle`` [rad] -> (3, 3)."""
    return Rotation.from_euler('x', angle).as_matrix()


def rot_y(angle: float) -> np.ndarray:
    """Rotation about y by ``angle`` [rad] -> (3, 3)."""
    return Rotation.from_euler('y', angle).as_matrix()


def rot_z(angle: float) -> np.ndarray:
    """Rotation about z by ``angle`` [rad] -> (3, 3)."""
    return Rotation.from_euler('z', angle).as_matrix()


def rotation_from_zyx_euler(z: float, y: float, x: float) -> np.ndarray:
    """Rotation of MATLAB ``eul2rotm([z y x])`` (default 'ZYX' order, intrinsic: Rz(z) Ry(y) Rx(x)) -> (3, 3).

    Args:
        z: Angle about z [rad], applied first in the intrinsic sense.
        y: Angle about the new y [rad].
        x: Angle about the newest x [rad].
    """
    return Rotation.from_euler('ZYX', [z, y, x]).as_matrix()


def zyx_euler_from_rotation(r: np.ndarray) -> tuple[float, float, float]:
    """ZYX Euler angles (z, y, x) [rad] of a rotation (3, 3): the inverse of :func:`rotation_from_zyx_euler`.

    y lies in [-pi/2, pi/2]; at the gimbal lock (|y| = pi/2) x is taken as 0.
    """
    with warnings.catch_warnings():  # SciPy says so when it sets x to 0 at the gimbal lock: that is the contract
        warnings.simplefilter('ignore', UserWarning)
        z, y, x = Rotation.from_matrix(np.asarray(r, dtype=float)).as_euler('ZYX')
    return float(z), float(y), float(x)


def slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation along the shorter arc from q0 to q1.

    Args:
        q0: Start quaternion(s) (..., 4), unit.
        q1: End quaternion(s) (..., 4), unit.
        t: Fraction(s) (...,); 0 gives q0, 1 gives q1. Values outside [0, 1] extrapolate
            along the same great circle at the same rate (used for C1 blends).

    Returns:
        Unit quaternions (..., 4) with w >= 0.
    """
    q0, q1, t = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float), np.asarray(t, dtype=float)
    shape = np.broadcast_shapes(q0.shape[:-1], q1.shape[:-1], t.shape)
    r0 = to_rotation(np.broadcast_to(q0, (*shape, 4)))
    turn = (r0.inv() * to_rotation(np.broadcast_to(q1, (*shape, 4)))).as_rotvec()  # angle <= pi: the shorter arc
    return from_rotation(r0 * Rotation.from_rotvec(np.broadcast_to(t, shape)[..., None] * turn))


def rotation_vectors(q_from: np.ndarray, q_to: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) [rad] in world axes of the turns from q_from to q_to, quaternions (..., 4):
    q_to = exp(v) q_from."""
    return (to_rotation(q_to) * to_rotation(q_from).inv()).as_rotvec()


def rotation_angle(r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """Angle [rad] (...,) of the relative rotation r0^T r1 of matrices (..., 3, 3)."""
    rel = Rotation.from_matrix(np.asarray(r0, dtype=float)).inv() * Rotation.from_matrix(np.asarray(r1, dtype=float))
    return rel.magnitude()


def as_quaternions(orientations: np.ndarray, count: int) -> np.ndarray:
    """Unit quaternions (count, 4) from rotations (count, 3, 3), quaternions (count, 4) or one of either.

    Raises:
        ValueError: A wrong shape, or a matrix that is not a proper rotation.
    """
    o = np.asarray(orientations, dtype=float)
    if o.shape in ((3, 3), (4,)):
        o = np.broadcast_to(o, (count, *o.shape))
    if o.shape == (count, 3, 3):
        bad = np.flatnonzero(~np.all(np.isclose(o @ np.swapaxes(o, 1, 2), np.eye(3), atol=1e-6),
                                     axis=(1, 2)) | (np.linalg.det(o) < 0))
        if bad.size:
            raise ValueError(f"orientation {bad[0]} is not a rotation matrix")
        return quat_from_matrix(o)
    if o.shape == (count, 4):
        return quat_normalize(o)
    raise ValueError(f"orientations must be (3, 3), (4,), ({count}, 3, 3) or ({count}, 4); "
                     f"got {o.shape}")
