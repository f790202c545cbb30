"""Bead path geometry: straight segments with circular corner blends, by arc length.

Only geometry: no timing and no IK. The path is tangent-continuous (C1) wherever a corner
has a radius > 0, so the tip can keep one speed along the whole bead; the curvature steps
between 0 and 1/r at the arc ends. The tip orientation follows the waypoint orientations by
SLERP, blended at each waypoint so that it is smooth too (see :meth:`GluePath.orientation`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur_common.quaternions import matrix_from_quat
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.orientation import as_quaternions, slerp

_MIN_SEGMENT = 1e-6  # [m] shorter segments are duplicate waypoints, not geometry
_MAX_TURN = math.pi - 1e-6  # [rad] a full reversal cannot be blended by an arc


@dataclass(frozen=True)
class CornerBlend:
    """How one corner was rounded.

    Attributes:
        waypoint: Index of the corner's waypoint in the input.
        turn_angle: Change of direction at the corner [rad] (0 = straight on).
        radius: Arc radius [m]; 0 leaves a sharp corner.
        setback: Distance [m] from the waypoint to each arc end along the segments.
        deviation: Distance [m] from the waypoint to the arc (at its middle).
        s_start: Arc length [m] where the arc begins.
        s_end: Arc length [m] where it ends.
        limited_by: 'radius', 'deviation' or 'segments' (half of the shorter neighbour),
            or 'straight' when there is nothing to blend.
    """

    waypoint: int
    turn_angle: float
    radius: float
    setback: float
    deviation: float
    s_start: float
    s_end: float
    limited_by: str


def _smoothstep(t: np.ndarray) -> np.ndarray:
    # quintic: zero first and second derivative at both ends, so blends are C2 in the weight
    t = np.clip(t, 0.0, 1.0)
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t))


@dataclass(frozen=True, eq=False)
class GluePath:
    """An arc-length parametrised bead path; build it with :func:`build_glue_path`.

    Attributes:
        vertices: Corner points (n, 3) [m] actually used (a closed path drops a last
            waypoint that repeats the first).
        closed: True if the path is a loop; s then wraps modulo ``length``.
        length: Total arc length L [m].
        corners: Blend report, one per blended (interior or, if closed, every) vertex.
        waypoint_s: Arc length (K,) [m] where the path passes each input waypoint (the arc
            middle at a corner); a closed loop starts after the first corner's arc.
        straight_s: Arc-length range (n_segments, 2) [m] of each segment's straight part.
        piece_s: Piece boundaries (P + 1,) [m].
        piece_arc: True for arc pieces (P,).
        piece_origin: Line start or arc centre (P, 3) [m].
        piece_e1: Line direction, or unit vector from the arc centre to its start (P, 3).
        piece_e2: Zero for lines, or the arc's unit tangent at its start (P, 3).
        piece_radius: Arc radius (P,) [m], 0 for lines.
        key_s: Orientation key arc lengths (N,) [m], strictly increasing.
        key_q: Key quaternions (N, 4), w-first.
        key_h: Half-width (N,) [m] of the blend window around each key.
    """

    vertices: np.ndarray
    closed: bool
    length: float
    corners: tuple[CornerBlend, ...]
    waypoint_s: np.ndarray
    straight_s: np.ndarray
    piece_s: np.ndarray
    piece_arc: np.ndarray
    piece_origin: np.ndarray
    piece_e1: np.ndarray
    piece_e2: np.ndarray
    piece_radius: np.ndarray
    key_s: np.ndarray
    key_q: np.ndarray
    key_h: np.ndarray

    def _arc_length(self, s: np.ndarray | float) -> np.ndarray:
        s = np.atleast_1d(np.asarray(s, dtype=float))
        if self.closed:
            return np.mod(s, self.length)
        slack = 1e-9 * max(self.length, 1.0)
        if np.any(s < -slack) or np.any(s > self.length + slack):
            raise ValueError(f"s must lie in [0, {self.length:.6f}] m for an open path; "
                             f"got [{s.min():.6f}, {s.max():.6f}]")
        return np.clip(s, 0.0, self.length)

    def _evaluate(self, s: np.ndarray | float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        ss = self._arc_length(s)
        j = np.clip(np.searchsorted(self.piece_s, ss, side="right") - 1, 0, len(self.piece_arc) - 1)
        t = (ss - self.piece_s[j])[:, None]
        o, e1, e2, r = self.piece_origin[j], self.piece_e1[j], self.piece_e2[j], self.piece_radius[j]
        arc = self.piece_arc[j][:, None]
        phi = np.where(arc, t / np.where(arc, r[:, None], 1.0), 0.0)
        radial = np.cos(phi) * e1 + np.sin(phi) * e2
        pos = np.where(arc, o + r[:, None] * radial, o + t * e1)
        tan = np.where(arc, -np.sin(phi) * e1 + np.cos(phi) * e2, e1)
        kappa = np.where(arc[:, 0], 1.0 / np.where(arc[:, 0], r, 1.0), 0.0)
        return pos, tan, kappa, -kappa[:, None] * radial

    def sample(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [m], unit tangent and curvature [1/m] at arc length s [m].

        Args:
            s: Scalar or (M,); open paths accept [0, L], closed ones wrap modulo L.

        Returns:
            (M, 3), (M, 3), (M,) arrays, or (3,), (3,), float for a scalar s.
        """
        pos, tan, kappa, _ = self._evaluate(s)
        if np.ndim(s) == 0:
            return pos[0], tan[0], float(kappa[0])
        return pos, tan, kappa

    def position(self, s: np.ndarray | float) -> np.ndarray:
        """Positions (M, 3) [m] at arc length s [m]; (3,) for a scalar s."""
        pos = self._evaluate(s)[0]
        return pos[0] if np.ndim(s) == 0 else pos

    def curvature_vector(self, s: np.ndarray | float) -> np.ndarray:
        """Curvature vector (M, 3) [1/m] = d(tangent)/ds, towards the arc centre; (3,) if scalar."""
        kvec = self._evaluate(s)[3]
        return kvec[0] if np.ndim(s) == 0 else kvec

    def derivatives(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (M, 3) [m], unit tangents (M, 3) and curvature vectors (M, 3) [1/m] in one evaluation."""
        pos, tan, _, kvec = self._evaluate(s)
        return pos, tan, kvec

    def quaternion(self, s: np.ndarray | float) -> np.ndarray:
        """Tip orientation as unit quaternions (M, 4), w first; (4,) for a scalar s.

        Between keys the orientation follows the SLERP geodesic at constant rate; around key
        k, inside +-key_h[k], it blends from the incoming to the outgoing geodesic with a
        quintic weight. Both geodesics pass the key's orientation at key_s[k], so the
        waypoint orientations are met exactly and the result is C2 along s.
        """
        ss = self._arc_length(s)
        ks, kq, kh = self.key_s, self.key_q, self.key_h
        if np.all(kq == kq[0]):  # one orientation for the whole bead (the seed's jobs): nothing to interpolate
            q = np.repeat(kq[:1], len(ss), axis=0)
            return q[0] if np.ndim(s) == 0 else q
        n = len(ks)
        i = np.clip(np.searchsorted(ks, ss, side="right") - 1, 0, n - 2)

        def geodesic(k: np.ndarray, x: np.ndarray) -> np.ndarray:
            return slerp(kq[k], kq[k + 1], (x - ks[k]) / (ks[k + 1] - ks[k]))

        q = geodesic(i, ss)
        for key, lo_side in ((i, True), (i + 1, False)):
            inner = (key >= 1) & (key <= n - 2)
            keyc = np.clip(key, 1, n - 2)
            h = kh[keyc]
            win = inner & (h > 0) & (ss < ks[keyc] + h if lo_side else ss > ks[keyc] - h)
            if not np.any(win):
                continue
            k, x = keyc[win], ss[win]
            weight = _smoothstep((x - (ks[k] - kh[k])) / (2.0 * kh[k]))
            q[win] = slerp(geodesic(k - 1, x), geodesic(k, x), weight)
        return q[0] if np.ndim(s) == 0 else q

    def orientation(self, s: np.ndarray | float) -> np.ndarray:
        """Tip rotation matrices (M, 3, 3) in the world at arc length s; (3, 3) if scalar."""
        return matrix_from_quat(self.quaternion(s))


def _blend(a: np.ndarray, b: np.ndarray, half_room: float, blend_radius: float | None,
           max_deviation: float | None) -> tuple[float, float, float, float, str]:
    """(turn, radius, setback, deviation, limited_by) for unit directions a -> b."""
    turn = math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))
    if turn < 1e-12:
        return turn, 0.0, 0.0, 0.0, "straight"
    half_tan = math.tan(turn / 2.0)
    limits = {"segments": half_room / half_tan}
    if blend_radius is not None:
        limits["radius"] = blend_radius
    if max_deviation is not None:
        limits["deviation"] = max_deviation / (1.0 / math.cos(turn / 2.0) - 1.0)
    limited_by = min(limits, key=limits.get)
    r = limits[limited_by]
    return turn, r, r * half_tan, r * (1.0 / math.cos(turn / 2.0) - 1.0), limited_by


def build_glue_path(waypoints: np.ndarray, orientations: np.ndarray, *,
                    blend_radius: float | None = None, max_deviation: float | None = 0.01,
                    closed: bool = False, close_tolerance: float = 0.02) -> GluePath:
    """Blend the waypoint polyline into a C1 bead path.

    Each corner gets the largest arc that respects every given limit: ``blend_radius``,
    ``max_deviation`` from the waypoint, and half of each neighbouring segment (so the
    blends of two corners never overlap and every segment keeps its midpoint).

    Args:
        waypoints: Tip positions (K, 3) [m], world frame, in visiting order.
        orientations: Tip rotations (K, 3, 3) or quaternions (K, 4) (w first), or one for all.
        blend_radius: Largest arc radius [m]; None for no radius limit, 0 for sharp corners.
        max_deviation: Largest distance [m] of the path from a corner waypoint, or None.
        closed: Make a loop. A last waypoint within ``close_tolerance`` [m] of the first
            is taken as its repeat and dropped (its orientation too); otherwise a closing
            segment is added. The loop starts where the first corner's arc ends.
        close_tolerance: See ``closed`` [m].

    Raises:
        ValueError: Malformed arrays or limits.
        PlanningError: Coincident consecutive waypoints or a 180 deg reversal.
    """
    w = np.asarray(waypoints, dtype=float)
    if w.ndim != 2 or w.shape[1] != 3 or len(w) < 2 or not np.all(np.isfinite(w)):
        raise ValueError(f"waypoints must be finite (K >= 2, 3) [m]; got shape {w.shape}")
    for name, value in (("blend_radius", blend_radius), ("max_deviation", max_deviation)):
        if value is not None and not value >= 0.0:
            raise ValueError(f"{name} {value} m must be >= 0")
    quats = as_quaternions(orientations, len(w))
    index = np.arange(len(w))
    if closed and len(w) > 2 and np.linalg.norm(w[-1] - w[0]) <= close_tolerance:
        index = index[:-1]
    vert = w[index]
    n = len(vert)
    if closed and n < 3:
        raise ValueError(f"a closed path needs 3 distinct waypoints; got {n}")
    n_seg = n if closed else n - 1
    seg = np.roll(vert, -1, axis=0)[:n_seg] - vert[:n_seg]
    seg_len = np.linalg.norm(seg, axis=1)
    for i in np.flatnonzero(seg_len < _MIN_SEGMENT):
        raise PlanningError(f"waypoints {index[i]} and {index[(i + 1) % n]} are "
                            f"{seg_len[i]:.2e} m apart (< {_MIN_SEGMENT} m)")
    direction = seg / seg_len[:, None]

    # corner k sits at vertex k, between segment k-1 (in) and k (out)
    corner_ids = range(n) if closed else range(1, n - 1)
    blends = {}
    for k in corner_ids:
        turn, r, d, dev, why = _blend(direction[k - 1], direction[k % n_seg],
                                      0.5 * min(seg_len[k - 1], seg_len[k % n_seg]),
                                      blend_radius, max_deviation)
        if turn > _MAX_TURN:
            raise PlanningError(f"waypoint {index[k]} turns the path back on itself "
                                f"({math.degrees(turn):.2f} deg > {math.degrees(_MAX_TURN):.4f})")
        blends[k] = (turn, r, d, dev, why)

    pieces: list[tuple[bool, np.ndarray, np.ndarray, np.ndarray, float, float]] = []
    corners, straight, key_of_vertex = [], np.zeros((n_seg, 2)), {0: 0.0}
    s = 0.0
    for i in range(n_seg):
        a, b = vert[i], vert[(i + 1) % n]
        d_start = blends[i][2] if i in blends else 0.0
        k = (i + 1) % n
        d_end = blends[k][2] if k in blends else 0.0
        start, length = a + d_start * direction[i], seg_len[i] - d_start - d_end
        straight[i] = (s, s + length)
        if length > 1e-12:
            pieces.append((False, start, direction[i], np.zeros(3), 0.0, length))
            s += length
        if k not in blends:  # path end of an open path
            key_of_vertex[k] = s
            continue
        turn, r, d, dev, why = blends[k]
        arc_len = r * turn
        if arc_len > 1e-12:
            out = direction[(i + 1) % n_seg]
            to_centre = out - (out @ direction[i]) * direction[i]
            to_centre /= np.linalg.norm(to_centre)
            tangent_pt = b - d * direction[i]
            pieces.append((True, tangent_pt + r * to_centre, -to_centre, direction[i], r, arc_len))
        corners.append(CornerBlend(int(index[k]), float(turn), float(r), float(d), float(dev), float(s),
                                   float(s + arc_len), why))
        key_of_vertex[k] = s + 0.5 * arc_len
        s += arc_len
    length = float(s)

    piece_s = np.concatenate([[0.0], np.cumsum([p[5] for p in pieces])])
    arcs = np.array([p[0] for p in pieces])
    # vertex k is waypoint k; a dropped repeat of the first waypoint maps to vertex 0
    waypoint_s = np.array([key_of_vertex[i if i < n else 0] for i in range(len(w))])

    # orientation keys; a loop is unrolled one key beyond each end so every key is interior
    ks = np.array([key_of_vertex[k] for k in range(n)])
    kq = quats[index]
    if closed:
        ks = np.concatenate([[ks[-1] - length, ks[0] - length], ks[1:], [ks[0], ks[1] + length]])
        kq = np.vstack([kq[-1:], kq[:1], kq[1:], kq[:1], kq[1:2]])
    for j in range(1, len(kq)):  # same hemisphere as the previous key: shortest rotations
        if kq[j] @ kq[j - 1] < 0.0:
            kq[j] = -kq[j]
    gaps = np.diff(ks)
    kh = np.zeros(len(ks))
    kh[1:-1] = 0.5 * np.minimum(gaps[:-1], gaps[1:])

    return GluePath(
        vertices=vert, closed=closed, length=length, corners=tuple(corners),
        waypoint_s=waypoint_s, straight_s=straight, piece_s=piece_s, piece_arc=arcs,
        piece_origin=np.array([p[1] for p in pieces]), piece_e1=np.array([p[2] for p in pieces]),
        piece_e2=np.array([p[3] for p in pieces]), piece_radius=np.array([p[4] for p in pieces]),
        key_s=ks, key_q=kq, key_h=kh)


def polyline_corners(waypoints: np.ndarray) -> tuple[float, np.ndarray]:
    """Length [m] of the open waypoint polyline (K, 3) and its turn angles (K - 2,) [rad]."""
    d = np.diff(np.asarray(waypoints, dtype=float), axis=0)
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    turns = np.arctan2(np.linalg.norm(np.cross(u[:-1], u[1:]), axis=1),
                       np.sum(u[:-1] * u[1:], axis=1))
    return float(np.linalg.norm(d, axis=1).sum()), turns
