"""Closed-form inverse kinematics of the UR arms, vectorised over many poses with numpy.

A UR arm is a 6R arm in the classic Denavit-Hartenberg form (a1 = a4 = a5 = d2 = d3 = 0,
alpha = (pi/2, 0, 0, pi/2, -pi/2, 0)): joints 2, 3 and 4 are parallel, so a pose is reached
in up to eight ways, one per choice of three signs. The solution follows the well-known
geometric derivation for these arms (e.g. K. P. Hawkins, "Analytic inverse kinematics for
the Universal Robots UR-5/UR-10 arms", 2013), written with our own symbols:

1. Wrist centre (origin of frame 5): p05 = p - d6 z6. Joint 1 puts it on the plane at d4
   from the base axis: ``p05x sin q1 - p05y cos q1 = d4`` (sign: shoulder).
2. Joint 5 from the flange height over that plane: ``cos q5 = (px sin q1 - py cos q1 - d4) / d6``
   (sign: wrist).
3. Joint 6 from the joint-2 axis z1 = (sin q1, -cos q1, 0) seen in the flange frame, which is
   ``(sin q5 cos q6, -sin q5 sin q6, cos q5)``.
4. Joints 2, 3 and 4: a planar 3R arm (a2, a3) in frame 1 reaching the origin of frame 3 (sign: elbow).

Frames: DH frame 0 is the UR controller's base frame, ``base_link`` turned by pi about z (as
in ``ur_description``), and DH frame 6 is ``tool0``. :class:`UrAnalyticIK` adds a fixed
tool offset (e.g. ``tool0`` to ``dispenser_tip``) and the pose of ``base_link`` in a world, so
its poses mean the same as those of the planner's Pinocchio kinematics. It lives with the description
(the DH parameters it solves) because both the planner and ur_sim's URScript (``movel``, ``get_inverse_kin``)
use it.

Branch index ``b`` (0..7) = 4 * shoulder + 2 * wrist + elbow, each bit 0 for the ``+acos``
root: bit wrist = 0 means q5 >= 0, bit elbow = 0 means q3 >= 0.
"""

from __future__ import annotations

import math

import numpy as np

from ur_sim_driver.description.params import DH

N_BRANCHES = 8
_TWO_PI = 2.0 * math.pi
# a cosine this far beyond +-1 is rounding at a workspace boundary, not an unreachable pose
_COS_SLACK = 1e-9
_BOTH = np.array([1.0, -1.0])  # the two roots of each arccos: + first
# base_link -> DH base frame: a half turn about z
_BASE_LINK_TO_DH = np.diag([-1.0, -1.0, 1.0, 1.0])


def wrap_angle(q: np.ndarray) -> np.ndarray:
    """Angles [rad] wrapped into [-pi, pi)."""
    return np.mod(np.asarray(q, dtype=float) + math.pi, _TWO_PI) - math.pi


def inverse_rigid(t: np.ndarray) -> np.ndarray:
    """Inverse of rigid transforms (..., 4, 4)."""
    r_t = np.swapaxes(t[..., :3, :3], -1, -2)
    out = np.zeros(np.shape(t))
    out[..., :3, :3] = r_t
    out[..., :3, 3] = -(r_t @ t[..., :3, 3, None])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def _dh_matrix(theta: np.ndarray, d: float, a: float, cos_alpha: float, sin_alpha: float) -> np.ndarray:
    """DH link transforms Rz(theta) Tz(d) Tx(a) Rx(alpha), (..., 4, 4) for theta (...,) [rad]."""
    ct, st = np.cos(theta), np.sin(theta)
    out = np.zeros((*np.shape(theta), 4, 4))
    out[..., 0, :] = np.stack([ct, -st * cos_alpha, st * sin_alpha, a * ct], axis=-1)
    out[..., 1, :] = np.stack([st, ct * cos_alpha, -ct * sin_alpha, a * st], axis=-1)
    out[..., 2, 1], out[..., 2, 2], out[..., 2, 3] = sin_alpha, cos_alpha, d
    out[..., 3, 3] = 1.0
    return out


class UrAnalyticIK:
    """All closed-form IK solutions of a UR arm's frame, rigidly fixed to ``tool0``.

    Args:
        dh: The arm's DH lengths [m] (``URParams.dh``).
        tool: Pose (4, 4) of the solved frame in ``tool0`` (e.g. the dispenser tip); identity if None.
        base_pose: World pose (4, 4) of ``base_link``; identity if None.
    """

    def __init__(self, dh: DH, tool: np.ndarray | None = None, base_pose: np.ndarray | None = None) -> None:
        if abs(dh.a2) < 1e-9 or abs(dh.a3) < 1e-9 or dh.d4 <= 0.0 or dh.d6 == 0.0:
            raise ValueError(f"DH lengths {dh} are not those of a UR arm (a2, a3 != 0, d4 > 0, d6 != 0)")
        self.dh = dh
        self.tool = np.eye(4) if tool is None else np.array(tool, dtype=float)
        base = np.eye(4) if base_pose is None else np.asarray(base_pose, dtype=float)
        for name, t in (("tool", self.tool), ("base_pose", base)):
            if t.shape != (4, 4) or not np.allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-9):
                raise ValueError(f"{name} must be a 4x4 rigid transform")
        self._world_from_dh = base @ _BASE_LINK_TO_DH
        self._dh_from_world = inverse_rigid(self._world_from_dh)
        self._tool_inv = inverse_rigid(self.tool)
        # (d, a, cos alpha, sin alpha) of the six links; alpha is exactly 0 or +-pi/2
        self._links = ((dh.d1, 0.0, 0.0, 1.0), (0.0, dh.a2, 1.0, 0.0), (0.0, dh.a3, 1.0, 0.0),
                       (dh.d4, 0.0, 0.0, 1.0), (dh.d5, 0.0, 0.0, -1.0), (dh.d6, 0.0, 1.0, 0.0))

    # ------------------------------------------------------------------ forward
    def fk(self, q: np.ndarray) -> np.ndarray:
        """World poses (..., 4, 4) of the frame at joint positions q (..., 6) [rad]."""
        q = np.asarray(q, dtype=float)
        t = np.broadcast_to(self._world_from_dh, (*q.shape[:-1], 4, 4))
        for i, link in enumerate(self._links):
            t = t @ _dh_matrix(q[..., i], *link)
        return t @ self.tool

    # ------------------------------------------------------------------ inverse
    def solve(self, poses: np.ndarray, branch: int | None = None) -> np.ndarray:
        """All eight solutions (..., 8, 6) [rad], each joint in [-pi, pi), of world poses (..., 4, 4).

        With ``branch`` (0..7) only that one, (..., 6). A branch that cannot reach a pose is NaN
        there. At a wrist singularity (sin q5 = 0) only q4 + q6 is determined; q6 is then 0.
        """
        if branch is None:
            shoulder = wrist = elbow = _BOTH
        elif 0 <= branch < N_BRANCHES:
            shoulder, wrist, elbow = (np.array([-1.0 if branch >> bit & 1 else 1.0]) for bit in (2, 1, 0))
        else:
            raise ValueError(f"branch {branch} must be in 0..{N_BRANCHES - 1}")
        d = self.dh
        t = self._dh_from_world @ np.asarray(poses, dtype=float) @ self._tool_inv
        p, x6, y6, z6 = t[..., :3, 3], t[..., :3, 0], t[..., :3, 1], t[..., :3, 2]
        # 1. shoulder: the wrist centre lies on the plane at d4 from the base axis
        p05 = p - d.d6 * z6
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_psi = d.d4 / np.hypot(p05[..., 0], p05[..., 1])
        psi = np.arccos(np.clip(cos_psi, -1.0, 1.0))
        q1 = (np.arctan2(p05[..., 1], p05[..., 0]) + math.pi / 2)[..., None] + shoulder * psi[..., None]
        s1, c1 = np.sin(q1), np.cos(q1)  # (..., 2) for both shoulder signs
        # 2. wrist: the flange's height over that plane
        cos5 = (p[..., None, 0] * s1 - p[..., None, 1] * c1 - d.d4) / d.d6
        a5 = np.arccos(np.clip(cos5, -1.0, 1.0))
        q5 = wrist * a5[..., None]  # (..., 2, 2)
        s5 = np.sin(q5)
        # 3. joint 6 from the joint-2 axis in the flange frame (scaling both atan2 arguments by sin q5
        #    instead of dividing keeps the quadrant and gives q6 = 0 at the singularity)
        zx = x6[..., None, 0] * s1 - x6[..., None, 1] * c1
        zy = y6[..., None, 0] * s1 - y6[..., None, 1] * c1
        q6 = np.arctan2(-zy[..., None] * s5, zx[..., None] * s5)
        # 4. the planar arm: frames 5 and 4 by undoing joints 6 and 5, then the origin of frame 3 seen
        #    in frame 1 (d4 behind frame 4, and frame 1 is base turned by q1 and lifted by d1)
        c5, c6, s6 = np.cos(q5)[..., None], np.cos(q6)[..., None], np.sin(q6)[..., None]
        s5 = s5[..., None]
        x6, y6, z6 = x6[..., None, None, :], y6[..., None, None, :], z6[..., None, None, :]
        x5, y5 = c6 * x6 - s6 * y6, s6 * x6 + c6 * y6
        x4, y4 = c5 * x5 - s5 * z6, s5 * x5 + c5 * z6
        w = p05[..., None, None, :] + d.d5 * y5 - d.d4 * y4
        s1, c1 = s1[..., None], c1[..., None]
        x, y = c1 * w[..., 0] + s1 * w[..., 1], w[..., 2] - d.d1
        q234 = np.arctan2(x4[..., 2], c1 * x4[..., 0] + s1 * x4[..., 1])
        cos3 = (x * x + y * y - d.a2 ** 2 - d.a3 ** 2) / (2.0 * d.a2 * d.a3)
        a3 = np.arccos(np.clip(cos3, -1.0, 1.0))
        q3 = elbow * a3[..., None]  # (..., 2, 2, 2)
        q2 = np.arctan2(y, x)[..., None] - np.arctan2(d.a3 * np.sin(q3), d.a2 + d.a3 * np.cos(q3))
        q4 = q234[..., None] - q2 - q3
        shape = q3.shape
        q = np.stack([np.broadcast_to(q1[..., :, None, None], shape), q2, q3, q4,
                      np.broadcast_to(q5[..., None], shape), np.broadcast_to(q6[..., None], shape)], axis=-1)
        q = wrap_angle(q)
        ok = ((cos_psi <= 1.0 + _COS_SLACK)[..., None, None] & (np.abs(cos5) <= 1.0 + _COS_SLACK)[..., None]
              & (np.abs(cos3) <= 1.0 + _COS_SLACK))  # (..., 2, 2): both elbow roots share it
        q[~np.broadcast_to(ok[..., None], shape)] = np.nan
        return q.reshape(*shape[:-3], N_BRANCHES, 6) if branch is None else q.reshape(*shape[:-3], 6)


def angular_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Largest per-joint angle (...,) [rad] between joint vectors (..., n), each difference wrapped."""
    return np.max(np.abs(wrap_angle(np.asarray(a) - np.asarray(b))), axis=-1)


def nearest_branch(solutions: np.ndarray, q: np.ndarray) -> tuple[int, float]:
    """Index of the solution (8, n) closest to q (n,) modulo whole turns, and that distance [rad].

    NaN rows (no solution) never match; (-1, inf) if none is valid.
    """
    dist = angular_distance(solutions, q)
    dist = np.where(np.isnan(dist), np.inf, dist)
    b = int(np.argmin(dist))
    return (b, float(dist[b])) if math.isfinite(dist[b]) else (-1, math.inf)


def follow_branch(solutions: np.ndarray, q_start: np.ndarray) -> np.ndarray:
    """Branches along a sequence of poses, made continuous: (M, ..., n) [rad] from ``solutions`` (M, ..., n).

    Each joint is unwrapped along the sequence (axis 0) and shifted by whole turns so that row 0
    is within pi of ``q_start`` (broadcast to (..., n)); from a branch's first NaN row on, its
    rows stay NaN.
    """
    q = np.array(solutions, dtype=float)
    ended = np.logical_or.accumulate(np.isnan(q).any(axis=-1), axis=0)
    q[ended] = np.nan
    q = np.unwrap(q, axis=0)  # a NaN row stays NaN and so do the ones after it
    return q + _TWO_PI * np.round((np.asarray(q_start, dtype=float) - q[0]) / _TWO_PI)
