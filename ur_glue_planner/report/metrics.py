"""Figures of merit of a glue bead, planned or executed: speed uniformity, path deviation, tracking error."""
from __future__ import annotations

import numpy as np


def speed_stats(positions: np.ndarray, speeds: np.ndarray, commanded: float, cruise: np.ndarray | None = None,
                band: float = 0.01) -> dict:
    """TCP speed statistics along a sampled bead.

    Args:
        positions: (K, 3) tip positions [m] in time order.
        speeds: (K,) tip speeds [m/s] at those samples.
        commanded: commanded TCP speed [m/s].
        cruise: (K,) bool, the samples between the start and end ramps (all when None); mean/min/max are over it.
        band: relative band for "within" (0.01 = 1 %).

    Returns:
        mean/min/max over the cruise samples [m/s], and `fraction_within_band`: the share of the whole bead's
        length (ramps included) travelled at a speed within `band` of `commanded`.
    """
    positions, speeds = np.asarray(positions, dtype=float), np.asarray(speeds, dtype=float)
    cruise = np.ones(len(speeds), bool) if cruise is None else np.asarray(cruise, bool)
    seg = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    # A segment counts as within the band when both of its end samples are.
    ok = np.abs(speeds - commanded) <= band * commanded
    within = ok[:-1] & ok[1:]
    total = float(seg.sum())
    v = speeds[cruise]
    return {'mean': float(v.mean()), 'min': float(v.min()), 'max': float(v.max()),
            'fraction_within_band': float(seg[within].sum() / total) if total > 0 else 0.0,
            'band': band, 'commanded': commanded, 'length': total}


def point_to_polyline_distance(points: np.ndarray, polyline: np.ndarray, chunk: int = 256) -> np.ndarray:
    """Distance [m] from each point (K, 3) to the polyline (M, 3) (nearest point on any segment)."""
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    ab2 = np.maximum((ab * ab).sum(axis=1), 1e-30)
    out = np.empty(len(points))
    for i in range(0, len(points), chunk):
        p = points[i:i + chunk, None, :]
        t = np.clip(((p - a) * ab).sum(axis=2) / ab2, 0.0, 1.0)
        nearest = a + t[..., None] * ab
        out[i:i + chunk] = np.linalg.norm(p - nearest, axis=2).min(axis=1)
    return out


def tracking_error(t_meas: np.ndarray, q_meas: np.ndarray, t_plan: np.ndarray, q_plan: np.ndarray) -> np.ndarray:
    """Per-joint max |measured - planned| [rad] over the planned time span, planned positions interpolated."""
    inside = (t_meas >= t_plan[0]) & (t_meas <= t_plan[-1])
    tm = t_meas[inside]
    planned = np.column_stack([np.interp(tm, t_plan, q_plan[:, j]) for j in range(q_plan.shape[1])])
    return np.abs(q_meas[inside] - planned).max(axis=0)
