"""Our own windshield: an analytic, doubly curved glass panel, its outline and its mesh.

Frames:
    world: the robot's world (UR5 base at the origin).
    local: the seed's STL frame, placed like the seed does with row vectors,
        ``p_world = Rx(55 deg)^T p_local + (0, 0.4, 0.15)`` (see :func:`seed_pose`).
    panel: the local frame turned about local x by ``panel_tilt``: u across the glass
        (= local x = world x), v up the glass, w out of the glue face. The glue face is the
        graph ``w = f(u, v)``, a polynomial fitted to the seed's 22 clicked waypoints.

The glue face is the upper one in the world; it is concave across the width, like the
inner face of a real windshield lying on a bonding fixture. The glass is ``thickness`` thick
below it, measured along the surface normal.

``meshes/windshield.stl`` is stored in the LOCAL frame, in metres; place it with
:func:`windshield_pose` (world-from-local). ``build_mesh(frame="world")`` gives a world copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from ur_glue_planner.orientation import rot_x
from ur_glue_planner.scene.windshield_outline import RoundedPolygon


def seed_pose(rx_deg: float = 55.0, location: tuple[float, float, float] = (0.0, 0.4, 0.15)
              ) -> np.ndarray:
    """World-from-local pose (4, 4) of MATLAB's ``points * rotationX(rx_deg) + location``.

    A row vector times R equals R^T times the column vector, hence the transpose.
    """
    pose = np.eye(4)
    pose[:3, :3] = rot_x(math.radians(rx_deg)).T
    pose[:3, 3] = location
    return pose


@dataclass(frozen=True)
class WindshieldModel:
    """Parameters of the glass panel; all lengths in metres.

    Attributes:
        corners_uv: Corners (u, v) of the glass outline before rounding, convex, in the order
            the bead visits the edges (default: bottom-left, top-left, top-right, bottom-right).
        corner_radius: Radius of the rounded glass corners [m].
        exponents: Monomial exponents (i, j) of the glue face ``w = sum c_k u^i v^j``.
        coefficients: The matching coefficients c_k [m^(1-i-j)].
        panel_tilt: Rotation of the panel frame about local x [rad].
        thickness: Glass thickness along the normal [m].
        world_from_local: Pose of the local frame in the world, 4x4 row tuples.
    """

    corners_uv: tuple[tuple[float, float], ...]
    corner_radius: float
    exponents: tuple[tuple[int, int], ...]
    coefficients: tuple[float, ...]
    panel_tilt: float
    thickness: float
    world_from_local: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        if len(self.exponents) != len(self.coefficients):
            raise ValueError(f"exponents ({len(self.exponents)}) and coefficients "
                             f"({len(self.coefficients)}) differ in length")
        if not self.thickness > 0.0:
            raise ValueError(f"thickness {self.thickness} m must be > 0")
        pose = np.asarray(self.world_from_local, dtype=float)
        if pose.shape != (4, 4) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3),
                                                   atol=1e-9):
            raise ValueError("world_from_local must be a 4x4 rigid transform")
        self.glass  # noqa: B018  (validates corners and radius early)

    # ------------------------------------------------------------------ frames
    @property
    def pose(self) -> np.ndarray:
        """World-from-local transform (4, 4)."""
        return np.array(self.world_from_local, dtype=float)

    @property
    def local_from_panel(self) -> np.ndarray:
        """Rotation (3, 3) whose columns are the panel axes u, v, w in the local frame."""
        c, s = math.cos(self.panel_tilt), math.sin(self.panel_tilt)
        return np.array([[1.0, 0.0, 0.0], [0.0, s, -c], [0.0, c, s]])

    @property
    def glass(self) -> RoundedPolygon:
        """The glass outline in the (u, v) plane."""
        return RoundedPolygon(np.asarray(self.corners_uv, dtype=float), self.corner_radius)

    def local_to_world(self, p: np.ndarray) -> np.ndarray:
        """Points (..., 3) from the local to the world frame."""
        pose = self.pose
        return np.asarray(p, dtype=float) @ pose[:3, :3].T + pose[:3, 3]

    def world_to_local(self, p: np.ndarray) -> np.ndarray:
        """Points (..., 3) from the world to the local frame."""
        pose = self.pose
        return (np.asarray(p, dtype=float) - pose[:3, 3]) @ pose[:3, :3]

    def _panel_to(self, uvw: np.ndarray, frame: str, direction: bool = False) -> np.ndarray:
        out = np.asarray(uvw) @ self.local_from_panel.T
        if frame == "local":
            return out
        if frame != "world":
            raise ValueError(f"frame {frame!r} must be 'world' or 'local'")
        return out @ self.pose[:3, :3].T if direction else self.local_to_world(out)

    # ------------------------------------------------------------------ surface
    def height(self, u: np.ndarray, v: np.ndarray, du: int = 0, dv: int = 0) -> np.ndarray:
        """Glue-face height w [m] over (u, v) [m], or its partial derivative du/dv times."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        out = np.zeros(u.shape)
        for (i, j), c in zip(self.exponents, self.coefficients):
            if i < du or j < dv:
                continue
            factor = math.perm(i, du) * math.perm(j, dv)
            out = out + c * factor * u ** (i - du) * v ** (j - dv)
        return out

    def surface_point(self, u: np.ndarray, v: np.ndarray, frame: str = "world") -> np.ndarray:
        """Points (..., 3) [m] of the glue face at panel coordinates u, v (...,) [m]."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        return self._panel_to(np.stack([u, v, self.height(u, v)], axis=-1), frame)

    def _panel_normal(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        n = np.stack(np.broadcast_arrays(-self.height(u, v, du=1), -self.height(u, v, dv=1),
                                         np.ones(np.shape(u))), axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def surface_normal(self, u: np.ndarray, v: np.ndarray, frame: str = "world") -> np.ndarray:
        """Unit normals (..., 3) of the glue face at (u, v), pointing out of the glass."""
        return self._panel_to(self._panel_normal(u, v), frame, direction=True)

    def principal_curvatures(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Principal curvatures (..., 2) [1/m] of the glue face, larger first.

        Positive means the face bends towards its normal (concave seen from the glue side).
        """
        fu, fv = self.height(u, v, du=1), self.height(u, v, dv=1)
        fuu, fuv, fvv = self.height(u, v, 2, 0), self.height(u, v, 1, 1), self.height(u, v, 0, 2)
        root = np.sqrt(1.0 + fu ** 2 + fv ** 2)
        e, f, g = 1.0 + fu ** 2, fu * fv, 1.0 + fv ** 2
        ll, mm, nn = fuu / root, fuv / root, fvv / root
        det = e * g - f ** 2
        gauss = (ll * nn - mm ** 2) / det
        mean = (e * nn - 2.0 * f * mm + g * ll) / (2.0 * det)
        disc = np.sqrt(np.maximum(mean ** 2 - gauss, 0.0))
        return np.stack([mean + disc, mean - disc], axis=-1)

    def _height_and_slope(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Height w and its partial derivatives dw/du, dw/dv over (u, v) [m], from one pass over the terms."""
        f, fu, fv = np.zeros(np.shape(u)), np.zeros(np.shape(u)), np.zeros(np.shape(u))
        for (i, j), c in zip(self.exponents, self.coefficients):
            ui, vj = u ** i, v ** j
            f = f + c * ui * vj
            if i:
                fu = fu + c * i * u ** (i - 1) * vj
            if j:
                fv = fv + c * j * ui * v ** (j - 1)
        return f, fu, fv

    def project(self, points: np.ndarray, frame: str = "world", iterations: int = 8
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest points on the (unbounded) glue face.

        Args:
            points: Points (M, 3) [m] in ``frame``.
            frame: 'world' or 'local'.
            iterations: Most Gauss-Newton steps; the face is nearly flat, so a few suffice (it
                stops once no point moves more than 1e-13 m).

        Returns:
            uv (M, 2) [m], foot points (M, 3) [m] and unit normals (M, 3), both in ``frame``.
        """
        p = np.atleast_2d(np.asarray(points, dtype=float))
        local = self.world_to_local(p) if frame == "world" else p
        q = local @ self.local_from_panel  # panel coordinates
        u, v = q[:, 0].copy(), q[:, 1].copy()
        f, fu, fv = self._height_and_slope(u, v)
        for _ in range(iterations):
            # normal equations of J = [[1, 0], [0, 1], [fu, fv]] for the residual (u, v, f) - q
            ru, rv, rw = u - q[:, 0], v - q[:, 1], f - q[:, 2]
            a, b, d = 1.0 + fu * fu, fu * fv, 1.0 + fv * fv
            gu, gv = ru + fu * rw, rv + fv * rw
            det = a * d - b * b
            step_u, step_v = (d * gu - b * gv) / det, (a * gv - b * gu) / det
            u, v = u - step_u, v - step_v
            f, fu, fv = self._height_and_slope(u, v)
            if max(np.abs(step_u).max(initial=0.0), np.abs(step_v).max(initial=0.0)) <= 1e-13:
                break
        normal = np.stack([-fu, -fv, np.ones_like(u)], axis=-1)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        return (np.stack([u, v], axis=-1), self._panel_to(np.stack([u, v, f], axis=-1), frame),
                self._panel_to(normal, frame, direction=True))

    # ------------------------------------------------------------------ outline
    def outline_uv(self, offset: float = 0.0, n_points: int = 256) -> np.ndarray:
        """Glass edge inset by ``offset`` [m], (n_points, 2) in (u, v), not repeating the start.

        Starts where the first corner's rounding ends and runs in corner order (the seed's
        bead direction), equally spaced in arc length of the (u, v) curve.
        """
        return self.glass.inset(offset).sample(n_points)

    def outline(self, offset: float = 0.0, n_points: int = 256, frame: str = "world"
                ) -> np.ndarray:
        """Closed polyline (n_points, 3) [m] on the glue face, ``offset`` [m] inside the edge.

        The inset is exact in the (u, v) plane; on the face it is longer by the slope factor,
        below 0.5 % for the default glass.
        """
        uv = self.outline_uv(offset, n_points)
        return self.surface_point(uv[:, 0], uv[:, 1], frame)

    def edge_distance(self, uv: np.ndarray) -> np.ndarray:
        """Signed distance (...,) [m] in the (u, v) plane to the glass edge, > 0 inside."""
        return self.glass.signed_distance(uv)


def _default_model() -> WindshieldModel:
    # Surface: least squares over the 22 waypoints, tilt chosen so the linear v term vanishes;
    # the fit leaves 0.08 mm max residual. Outline: the bead's trapezoid pushed 30 mm out.
    return WindshieldModel(
        corners_uv=((-0.345, -0.025), (-0.435, 0.48), (0.435, 0.48), (0.345, -0.025)),
        corner_radius=0.05,
        exponents=((0, 0), (2, 0), (0, 2), (2, 1)),
        coefficients=(-0.0100, 0.0951, -0.0121, 0.0714),
        panel_tilt=math.radians(22.5),
        thickness=0.005,
        world_from_local=tuple(tuple(row) for row in seed_pose().tolist()),
    )


DEFAULT_WINDSHIELD: WindshieldModel = _default_model()


def windshield_pose(model: WindshieldModel = DEFAULT_WINDSHIELD) -> np.ndarray:
    """World-from-local pose (4, 4) that places ``meshes/windshield.stl`` in the world."""
    return model.pose


def local_to_world(p: np.ndarray, model: WindshieldModel = DEFAULT_WINDSHIELD) -> np.ndarray:
    """Points (..., 3) [m] from the windshield's local frame to the world."""
    return model.local_to_world(p)


def world_to_local(p: np.ndarray, model: WindshieldModel = DEFAULT_WINDSHIELD) -> np.ndarray:
    """Points (..., 3) [m] from the world to the windshield's local frame."""
    return model.world_to_local(p)


def fan_slab(boundary: np.ndarray, resolution: float, min_rings: int = 1
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangulation of a slab over a star-shaped outline (shared by the whole panel and its pieces).

    The top face is meshed on rings that shrink ``boundary`` towards its centroid, about ``resolution`` [m]
    apart; the bottom face repeats the top's vertices at index offset ``len(uv)``.

    Args:
        boundary: (n, 2) outline points, counter-clockwise.
        resolution: ring spacing [m].
        min_rings: fewest rings.

    Returns:
        uv (1 + m n, 2) top vertices; top faces (k, 3), counter-clockwise seen from +w; side-wall faces
        joining the top rim to the bottom rim.
    """
    n = len(boundary)
    center = boundary.mean(axis=0)
    m = max(min_rings, math.ceil(np.linalg.norm(boundary - center, axis=1).max() / resolution))
    scales = np.arange(1, m + 1) / m
    uv = np.vstack([center[None], (center + scales[:, None, None] * (boundary - center)).reshape(-1, 2)])
    nv = len(uv)

    def ring(k: int, j: np.ndarray) -> np.ndarray:
        return 1 + (k - 1) * n + j % n

    j = np.arange(n)
    faces = [np.column_stack([np.zeros(n, dtype=int), ring(1, j), ring(1, j + 1)])]
    for k in range(1, m):
        a, b, c, d = ring(k, j), ring(k, j + 1), ring(k + 1, j + 1), ring(k + 1, j)
        faces += [np.column_stack([a, d, c]), np.column_stack([a, c, b])]
    rim, rim_next = ring(m, j), ring(m, j + 1)
    side = np.vstack([np.column_stack([rim, rim_next + nv, rim_next]),
                      np.column_stack([rim, rim + nv, rim_next + nv])])
    return uv, np.vstack(faces), side


def build_mesh(model: WindshieldModel = DEFAULT_WINDSHIELD, resolution: float = 0.03,
               frame: str = "world") -> trimesh.Trimesh:
    """Closed (watertight) triangle mesh of the glass with outward normals.

    The glue face is triangulated on rings that shrink the outline towards its centroid
    (the outline is convex, hence star-shaped); the back face is the glue face moved by
    ``thickness`` along the inward normal, and a wall joins the two boundaries.

    Args:
        model: The windshield.
        resolution: Approximate edge length [m] along the outline and between rings.
        frame: 'world' or 'local'.
    """
    if not resolution > 0.0:
        raise ValueError(f"resolution {resolution} m must be > 0")
    glass = model.glass
    n = max(16, math.ceil(glass.length / resolution))
    boundary = glass.sample(n)
    uv, top_faces, side = fan_slab(boundary, resolution, min_rings=2)
    top = np.column_stack([uv, model.height(uv[:, 0], uv[:, 1])])
    bottom = top - model.thickness * model._panel_normal(uv[:, 0], uv[:, 1])
    if glass.orientation < 0:  # keep the glue face's normals along +w
        top_faces, side = top_faces[:, ::-1], side[:, ::-1]
    all_faces = np.vstack([top_faces, top_faces[:, ::-1] + len(uv), side])
    vertices = model._panel_to(np.vstack([top, bottom]), frame)
    return trimesh.Trimesh(vertices=vertices, faces=all_faces, process=True)


def write_stl(path: str | Path, model: WindshieldModel = DEFAULT_WINDSHIELD,
              resolution: float = 0.03, frame: str = "local") -> Path:
    """Write the glass as a binary STL [m] (local frame by default); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    build_mesh(model, resolution, frame).export(str(path), file_type="stl")
    return path


def generate_default_mesh(out_path: str | Path = "meshes/windshield.stl") -> Path:
    """Write the default windshield, local frame, to ``out_path`` (meshes/windshield.stl)."""
    return write_stl(out_path, DEFAULT_WINDSHIELD, frame="local")
