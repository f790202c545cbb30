"""Rotation helpers: elementary rotations, ZYX Euler angles, unit quaternions, SLERP.

Quaternions are scalar-first ``(w, x, y, z)`` like MATLAB's ``quaternion``/``rotm2quat``;
ROS messages order them ``(x, y, z, w)``, so convert at the ROS boundary only.
All functions accept a leading batch shape, e.g. quaternions (..., 4), matrices (..., 3, 3).
"""

from __future__ import annotations

import numpy as np

# Below this angle [rad] between two quaternions SLERP falls back to a normalised lerp,
# whose error there is far below float resolution of the angle itself.
_SMALL_ANGLE = 1e-8


def rot_x(angle: float) -> np.ndarray:
    """Rotation about x by ``angle`` [rad] -> (3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    """Rotation about y by ``angle`` [rad] -> (3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    """Rotation about z by ``angle`` [rad] -> (3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_zyx_euler(z: float, y: float, x: float) -> np.ndarray:
    """Rotation of MATLAB ``eul2rotm([z y x])`` (default 'ZYX' order) -> (3, 3).

    Args:
        z: Angle about z [rad], applied first in the intrinsic sense.
        y: Angle about the new y [rad].
        x: Angle about the newest x [rad].
    """
    return rot_z(z) @ rot_y(y) @ rot_x(x)


def zyx_euler_from_rotation(r: np.ndarray) -> tuple[float, float, float]:
    """ZYX Euler angles (z, y, x) [rad] of a rotation (3, 3): the inverse of :func:`rotation_from_zyx_euler`.

    y lies in [-pi/2, pi/2]; at the gimbal lock (|y| = pi/2) x is taken as 0.
    """
    r = np.asarray(r, dtype=float)
    sy = float(np.clip(-r[2, 0], -1.0, 1.0))
    y = float(np.arcsin(sy))
    if abs(sy) < 1.0 - 1e-12:
        return float(np.arctan2(r[1, 0], r[0, 0])), y, float(np.arctan2(r[2, 1], r[2, 2]))
    return float(np.arctan2(-r[0, 1], r[1, 1])), y, 0.0


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternion(s) (..., 4) with non-negative w (a canonical sign)."""
    q = np.asarray(q, dtype=float)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(norm < 1e-12):
        raise ValueError("quaternion of (near) zero norm cannot be normalised")
    q = q / norm
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` of quaternions (..., 4)."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, dtype=float), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, dtype=float), -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate (= inverse for unit quaternions) of quaternions (..., 4)."""
    return np.asarray(q, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])


def matrix_from_quat(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4) (normalised first)."""
    w, x, y, z = np.moveaxis(quat_normalize(q), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=-2)


def quat_from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4), w >= 0, of rotation matrices (..., 3, 3).

    Uses the largest of the four squared components as pivot, so it stays accurate
    for rotations near 180 deg where the trace formula loses all precision.
    """
    m = np.asarray(m, dtype=float)
    batch = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    diag = np.stack([m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]], axis=-1)
    trace = diag.sum(axis=-1)
    # 4*w^2, 4*x^2, 4*y^2, 4*z^2 up to the same scale; pick the biggest per matrix
    squares = np.stack([1 + trace, 1 + 2 * diag[:, 0] - trace,
                        1 + 2 * diag[:, 1] - trace, 1 + 2 * diag[:, 2] - trace], axis=-1)
    pivot = np.argmax(squares, axis=-1)
    q = np.empty((m.shape[0], 4))
    for k in range(4):
        sel = pivot == k
        if not np.any(sel):
            continue
        r = m[sel]
        s = 2.0 * np.sqrt(squares[sel, k])  # = 4 * |component k|
        off = {  # the other three components from the off-diagonal sums/differences
            0: (r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]),
            1: (r[:, 2, 1] - r[:, 1, 2], r[:, 0, 1] + r[:, 1, 0], r[:, 0, 2] + r[:, 2, 0]),
            2: (r[:, 0, 2] - r[:, 2, 0], r[:, 0, 1] + r[:, 1, 0], r[:, 1, 2] + r[:, 2, 1]),
            3: (r[:, 1, 0] - r[:, 0, 1], r[:, 0, 2] + r[:, 2, 0], r[:, 1, 2] + r[:, 2, 1]),
        }[k]
        others = [i for i in range(4) if i != k]
        q[sel, k] = s / 4.0
        for i, value in zip(others, off):
            q[sel, i] = value / s
    return quat_normalize(q).reshape(*batch, 4)


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
    q0 = np.asarray(q0, dtype=float)
    q1 = np.asarray(q1, dtype=float)
    t = np.asarray(t, dtype=float)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    # q and -q are the same rotation; flipping keeps the rotation angle <= 180 deg
    q1 = np.where(dot < 0.0, -q1, q1)
    dot = np.clip(np.abs(dot), -1.0, 1.0)
    theta = np.arccos(dot)
    sin_theta = np.sin(theta)
    small = theta < _SMALL_ANGLE
    safe_sin = np.where(small, 1.0, sin_theta)
    w0 = np.where(small, 1.0 - t, np.sin((1.0 - t) * theta) / safe_sin)
    w1 = np.where(small, t, np.sin(t * theta) / safe_sin)
    return quat_normalize(w0 * q0 + w1 * q1)


def rotation_angle(r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """Angle [rad] (...,) of the relative rotation r0^T r1 of matrices (..., 3, 3)."""
    rel = np.swapaxes(np.asarray(r0), -1, -2) @ np.asarray(r1)
    cos = (np.trace(rel, axis1=-2, axis2=-1) - 1.0) / 2.0
    return np.arccos(np.clip(cos, -1.0, 1.0))


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
