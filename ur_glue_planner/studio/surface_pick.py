"""Points on the glue face from the browser: a click ray's hit on the glass, and a dragged point put back onto it.

The glue face is the windshield model's analytic surface ``w = f(u, v)`` (the mesh is its triangulation, within
0.03 mm), so a hit lies on the glass to the solver's tolerance; points outside the glass outline are refused.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_glue_planner.scene.windshield import WindshieldModel


@dataclass(frozen=True)
class SurfacePoint:
    """A point of the glue face: position (3,) [m] and unit normal (3,) in the world, panel coordinates uv (2,) [m]."""

    position: np.ndarray
    normal: np.ndarray
    uv: np.ndarray


def ray_hit(model: WindshieldModel, origin, direction, iterations: int = 30,
            tol: float = 1e-10) -> SurfacePoint | None:
    """First intersection of the ray ``origin + t direction`` (t > 0, world [m]) with the glue face inside the glass.

    Newton's method on ``g(t) = w(t) - f(u(t), v(t))`` from the hit of the face's tangent plane at the panel
    origin; the face is nearly flat, so a few steps converge. None if the ray misses the glass.
    """
    o = np.asarray(origin, dtype=float)
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    to_panel = model.pose[:3, :3] @ model.local_from_panel  # world-from-panel rotation
    op = (o - model.pose[:3, 3]) @ to_panel
    dp = d @ to_panel
    if abs(dp[2]) < 1e-9:
        return None
    t = (float(model.height(0.0, 0.0)) - op[2]) / dp[2]
    for _ in range(iterations):
        u, v = op[0] + t * dp[0], op[1] + t * dp[1]
        g = op[2] + t * dp[2] - float(model.height(u, v))
        dg = dp[2] - float(model.height(u, v, du=1)) * dp[0] - float(model.height(u, v, dv=1)) * dp[1]
        if abs(dg) < 1e-12:
            return None
        step = g / dg
        t -= step
        if abs(step) < tol:
            break
    else:
        return None
    if t <= 0.0:
        return None
    uv = np.array([op[0] + t * dp[0], op[1] + t * dp[1]])
    if model.edge_distance(uv) < 0.0:
        return None
    return SurfacePoint(model.surface_point(uv[0], uv[1]), model.surface_normal(uv[0], uv[1]), uv)


def onto_surface(model: WindshieldModel, point) -> SurfacePoint | None:
    """The glue-face point nearest to ``point`` (3,) [m], or None if it lies outside the glass outline."""
    uv, foot, normal = model.project(np.asarray(point, dtype=float)[None, :])
    if model.edge_distance(uv[0]) < 0.0:
        return None
    return SurfacePoint(foot[0], normal[0], uv[0])
