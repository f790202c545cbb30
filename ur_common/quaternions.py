"""Unit quaternions as (w, x, y, z) with w >= 0 (MuJoCo's and viser's order, one sign per rotation), through SciPy's
``Rotation``: the one place where ur_sim_driver and ur_glue_planner turn rotation matrices into quaternions and back.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def to_rotation(q: np.ndarray) -> Rotation:
    """SciPy rotation(s) of quaternions (..., 4) (normalised on the way).

    Raises:
        ValueError: a quaternion of (near) zero norm.
    """
    q = np.asarray(q, dtype=float)
    if np.any(np.linalg.norm(q, axis=-1) < 1e-12):
        raise ValueError('quaternion of (near) zero norm cannot be normalised')
    return Rotation.from_quat(q, scalar_first=True)


def from_rotation(r: Rotation) -> np.ndarray:
    """Unit quaternions (..., 4), w >= 0, of SciPy rotation(s) `r`."""
    return r.as_quat(canonical=True, scalar_first=True)


def quat_normalize(q: np.ndarray) -> np.ndarray:
    """Unit quaternion(s) (..., 4) with w >= 0."""
    return from_rotation(to_rotation(q))


def matrix_from_quat(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4) (normalised first)."""
    return to_rotation(q).as_matrix()


def quat_from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4), w >= 0, of rotation matrices (..., 3, 3)."""
    return from_rotation(Rotation.from_matrix(np.asarray(m, dtype=float)))
