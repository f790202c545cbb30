"""Convex polygon with rounded corners in a plane: the windshield's glass edge in (u, v).

An inward offset of such a shape is again one: the edges move in by the offset, the corner
arcs keep their centres and lose the offset from their radius (down to sharp corners).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def _offset_corners(corners: np.ndarray, normals: np.ndarray, d: float) -> np.ndarray:
    """Corners (N, 2) of the polygon whose edges moved by d along inward normals (N, 2)."""
    heights = np.sum(normals * corners, axis=1) + d  # edge i: normals[i] . x = heights[i]
    out = np.empty_like(corners)
    for i in range(len(corners)):
        a = np.array([normals[i - 1], normals[i]])
        out[i] = np.linalg.solve(a, [heights[i - 1], heights[i]])
    return out


@dataclass(frozen=True, eq=False)
class RoundedPolygon:
    """Convex polygon (corners (N, 2) [m], either orientation) with corner radius [m]."""

    corners: np.ndarray
    radius: float
    orientation: int = field(init=False)  # +1 counter-clockwise, -1 clockwise
    normals: np.ndarray = field(init=False)  # inward unit normal of edge i -> i+1, (N, 2)
    centers: np.ndarray = field(init=False)  # corner arc centres (N, 2)

    def __post_init__(self) -> None:
        c = np.asarray(self.corners, dtype=float)
        if c.ndim != 2 or c.shape[1] != 2 or len(c) < 3:
            raise ValueError(f"corners must be (N >= 3, 2), got {c.shape}")
        edges = np.roll(c, -1, axis=0) - c
        cross = edges[:, 0] * np.roll(edges, -1, axis=0)[:, 1] - \
            edges[:, 1] * np.roll(edges, -1, axis=0)[:, 0]
        if not (np.all(cross > 0) or np.all(cross < 0)):
            raise ValueError("corners must form a strictly convex polygon")
        if self.radius < 0.0:
            raise ValueError(f"corner radius {self.radius} m must be >= 0")
        sign = 1 if cross[0] > 0 else -1
        unit = edges / np.linalg.norm(edges, axis=1, keepdims=True)
        normals = sign * np.column_stack([-unit[:, 1], unit[:, 0]])
        object.__setattr__(self, "corners", c)
        object.__setattr__(self, "orientation", sign)
        object.__setattr__(self, "normals", normals)
        centers = _offset_corners(c, normals, self.radius)
        if np.any(np.sum((np.roll(centers, -1, axis=0) - centers) * edges, axis=1) < 0.0):
            raise ValueError(f"corner radius {self.radius} m does not fit in the polygon")
        object.__setattr__(self, "centers", centers)

    def inset(self, offset: float) -> RoundedPolygon:
        """The shape shrunk by ``offset`` [m] (>= 0) everywhere."""
        if offset < 0.0:
            raise ValueError(f"offset {offset} m must be >= 0")
        try:
            return RoundedPolygon(_offset_corners(self.corners, self.normals, offset),
                                  max(self.radius - offset, 0.0))
        except (ValueError, np.linalg.LinAlgError) as exc:
            raise ValueError(f"offset {offset} m leaves no glass inside the outline") from exc

    def _pieces(self) -> list[tuple[np.ndarray, np.ndarray | None, float, float, float]]:
        """Edges and arcs from corner 0's arc end, in corner order.

        Each is (start, end, nan, 0, length) for an edge or (centre, None, start angle [rad],
        signed sweep [rad], length) for an arc.
        """
        n, r = len(self.corners), self.radius
        pieces = []
        for i in range(n):
            k = (i + 1) % n
            start = self.centers[i] - r * self.normals[i]
            end = self.centers[k] - r * self.normals[i]
            pieces.append((start, end, math.nan, 0.0, float(np.linalg.norm(end - start))))
            d_in, d_out = -self.normals[i], -self.normals[k]  # from the centre to the arc
            sweep = math.atan2(d_in[0] * d_out[1] - d_in[1] * d_out[0], float(d_in @ d_out))
            pieces.append((self.centers[k], None, math.atan2(d_in[1], d_in[0]), sweep,
                           r * abs(sweep)))
        return pieces

    @property
    def length(self) -> float:
        """Perimeter [m]."""
        return sum(p[4] for p in self._pieces())

    def sample(self, n_points: int) -> np.ndarray:
        """Points (n_points, 2) equally spaced in arc length, start not repeated."""
        if n_points < 3:
            raise ValueError(f"n_points {n_points} must be >= 3")
        pieces = self._pieces()
        lengths = np.array([p[4] for p in pieces])
        bounds = np.concatenate([[0.0], np.cumsum(lengths)])
        s = np.arange(n_points) * bounds[-1] / n_points
        idx = np.clip(np.searchsorted(bounds, s, side="right") - 1, 0, len(pieces) - 1)
        out = np.empty((n_points, 2))
        for i, (a, b, phi0, sweep, length) in enumerate(pieces):
            sel = idx == i
            t = (s[sel] - bounds[i]) / length if length > 0 else np.zeros(np.count_nonzero(sel))
            if b is not None:  # straight edge
                out[sel] = a + t[:, None] * (b - a)
            else:
                phi = phi0 + t * sweep
                out[sel] = a + self.radius * np.column_stack([np.cos(phi), np.sin(phi)])
        return out

    def signed_distance(self, points: np.ndarray) -> np.ndarray:
        """Distance (...,) [m] from points (..., 2) to the boundary, positive inside."""
        p = np.asarray(points, dtype=float)
        flat = p.reshape(-1, 2)
        q, outward = self.centers, -self.normals
        line = np.einsum("nk,mnk->mn", outward, flat[:, None, :] - q[None])
        inside = line.max(axis=1)  # exact for points inside the centre polygon
        a, b = q[None], np.roll(q, -1, axis=0)[None]
        ab = b - a
        t = np.clip(np.sum((flat[:, None] - a) * ab, axis=2) / np.sum(ab * ab, axis=2), 0, 1)
        seg = np.linalg.norm(flat[:, None] - (a + t[..., None] * ab), axis=2).min(axis=1)
        sd_centres = np.where(inside <= 0.0, inside, seg)
        return (self.radius - sd_centres).reshape(p.shape[:-1])
