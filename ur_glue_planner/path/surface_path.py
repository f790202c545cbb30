"""A bead path laid onto the glass: every point of the planned path moved onto the windshield, and the tip placed
on the nozzle axis through that point, the job's standoff above the glass (measured along the normal).

Clicked waypoints lie on the glass, but the straight stretches between them are chords of a curved surface: on
seed 1's 22 clicks they rise up to 2 mm above the concave glass. The glue, leaving along the tilted nozzle axis,
then lands up to 0.65 mm beside the clicked line. Walking the path's projection instead keeps the tip at the
standoff everywhere and the bead on the line: the tip backs off along the (tilted) nozzle axis, not along the
normal, so that the material, which leaves along the axis, lands on the line at any standoff. The projection is
smooth (the glass is an analytic surface), so the tangent and the curvature vector are taken by central differences
of the projected points (h = 0.1 mm and 1 mm: errors far below the IK tolerance); the arc length is the original
path's, which differs from the projection's own by less than 0.01 %.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_glue_planner.path.glue_path import GluePath
from ur_glue_planner.scene.windshield import WindshieldModel

_H_TANGENT = 1e-4  # [m]
_H_CURVATURE = 1e-3  # [m]


@dataclass(frozen=True, eq=False)
class SurfacePath:
    """``path`` projected onto ``surface`` at ``standoff`` [m] along its normal; GluePath's interface.

    Attributes:
        path: The planned path (corners rounded). surface: The windshield. standoff: [m] above the glass.
        axis: The nozzle axis (3,) in the tip frame (it points at the glass).
    """

    path: GluePath
    surface: WindshieldModel
    standoff: float
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    @property
    def closed(self) -> bool:
        return self.path.closed

    @property
    def length(self) -> float:
        return self.path.length

    @property
    def waypoint_s(self) -> np.ndarray:
        return self.path.waypoint_s

    def position(self, s: np.ndarray | float) -> np.ndarray:
        """Projected points (M, 3) [m] (or (3,) for a scalar s)."""
        ss = np.atleast_1d(np.asarray(s, dtype=float))
        pos = np.atleast_2d(self.path.sample(ss)[0])
        _, foot, normal = self.surface.project(pos)
        out = foot
        if self.standoff > 0.0:
            axis = np.atleast_3d(self.path.orientation(ss)).reshape(-1, 3, 3) @ np.asarray(self.axis, dtype=float)
            along = self.standoff / np.maximum(-np.sum(axis * normal, axis=1), 0.1)  # axis length to that height
            out = foot - along[:, None] * axis
        return out[0] if np.ndim(s) == 0 else out

    def derivatives(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions (M, 3) [m], unit tangents (M, 3) and curvature vectors (M, 3) [1/m] in one evaluation."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        if not self.closed:  # keep the stencils inside an open path
            s_t = np.clip(s, _H_TANGENT, self.length - _H_TANGENT)
            s_c = np.clip(s, _H_CURVATURE, self.length - _H_CURVATURE)
        else:
            s_t = s_c = s
        # every stencil point projected in one call (a closed path's curvature stencil is centred on s itself)
        stencil = [s, s_t + _H_TANGENT, s_t - _H_TANGENT, s_c + _H_CURVATURE, s_c - _H_CURVATURE]
        if not self.closed:
            stencil.append(s_c)
        points = self.position(np.concatenate(stencil)).reshape(len(stencil), len(s), 3)
        pos, t_plus, t_minus, c_plus, c_minus = points[:5]
        c_mid = points[5] if not self.closed else pos
        d1 = (t_plus - t_minus) / (2 * _H_TANGENT)
        tan = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
        d2 = (c_plus - 2 * c_mid + c_minus) / _H_CURVATURE ** 2
        kvec = d2 - np.sum(d2 * tan, axis=1, keepdims=True) * tan  # the part across the tangent
        return pos, tan, kvec

    def sample(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [m], unit tangent and curvature [1/m], as GluePath.sample."""
        pos, tan, kvec = self.derivatives(s)
        kappa = np.linalg.norm(kvec, axis=1)
        if np.ndim(s) == 0:
            return pos[0], tan[0], float(kappa[0])
        return pos, tan, kappa

    def curvature_vector(self, s: np.ndarray | float) -> np.ndarray:
        kvec = self.derivatives(s)[2]
        return kvec[0] if np.ndim(s) == 0 else kvec

    def quaternion(self, s: np.ndarray | float) -> np.ndarray:
        return self.path.quaternion(s)

    def orientation(self, s: np.ndarray | float) -> np.ndarray:
        return self.path.orientation(s)
