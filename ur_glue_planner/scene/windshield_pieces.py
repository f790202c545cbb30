"""Convex collision pieces of the windshield.

MuJoCo collides every mesh as its convex hull. The glue face is concave across the width, so
the hull of the whole panel (``meshes/windshield.stl``) spans the glass like a lid, 1-2 cm above
it in the middle. This module cuts the panel into a grid of tiles in the panel parameters
(u, v), each tile clipped to the (rounded) glass outline, and turns every tile into a closed
slab of the glass (top = glue face, bottom = back face, side walls). A tile is small enough
that the hull of its slab stays within ``max_deviation`` (0.5 mm) of the glue face.

Deviation is measured on the hulls MuJoCo itself computes (:func:`convex_hulls`): the highest
hull top over a dense (u, v) grid minus the analytic height ``w = f(u, v)``, in the panel's w
direction (the distance along the surface normal is smaller by the cosine of the slope).

The pieces are written like ``meshes/windshield.stl``: binary STL in metres, LOCAL frame, so
they take the same pose (:func:`ur_glue_planner.scene.windshield.windshield_pose`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD, WindshieldModel, fan_slab

MAX_DEVIATION = 0.0005  # [m] allowed height of a piece's hull above the glue face
DEFAULT_GRID = (12, 2)  # tiles across (u) and up (v) the glass


@dataclass(frozen=True, eq=False)
class Piece:
    """One convex piece of the glass.

    Attributes:
        cell_uv: Its outline (K, 2) [m] in (u, v), convex, counter-clockwise.
        mesh: Closed slab (top, bottom and side faces) with outward normals, LOCAL frame [m].
    """

    cell_uv: np.ndarray
    mesh: trimesh.Trimesh


def outline_polygon(model: WindshieldModel = DEFAULT_WINDSHIELD, arc_step: float = 0.005
                    ) -> np.ndarray:
    """The glass outline (N, 2) [m] in (u, v) as a convex polygon, counter-clockwise.

    Straight edges stay single segments; the corner arcs are sampled every ``arc_step`` [m]
    with vertices on the arc (inscribed: sag ``r (1 - cos(step / 2r))``, 0.06 mm by default).
    """
    glass = model.glass
    r, centers, normals = glass.radius, glass.centers, glass.normals
    points = []
    for k in range(len(centers)):
        d_in, d_out = -normals[k - 1], -normals[k]  # from the arc centre to the arc ends
        sweep = math.atan2(d_in[0] * d_out[1] - d_in[1] * d_out[0], float(d_in @ d_out))
        n = max(1, math.ceil(abs(sweep) * r / arc_step)) if r > 0.0 else 0
        phi = math.atan2(d_in[1], d_in[0]) + sweep * np.linspace(0.0, 1.0, n + 1)
        points.append(centers[k] + r * np.column_stack([np.cos(phi), np.sin(phi)]))
    poly = _dedupe(np.vstack(points))
    return poly if _signed_area(poly) > 0.0 else poly[::-1]


def _signed_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _dedupe(poly: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Drop consecutive (cyclically) repeated vertices."""
    keep = np.linalg.norm(poly - np.roll(poly, 1, axis=0), axis=1) > tol
    return poly[keep] if keep.any() else poly[:1]


def _clip(poly: np.ndarray, axis: int, bound: float, keep_below: bool) -> np.ndarray:
    """Sutherland-Hodgman: the part of the convex polygon with x[axis] <= bound (or >=)."""
    if len(poly) == 0:
        return poly
    s = (bound - poly[:, axis]) if keep_below else (poly[:, axis] - bound)  # >= 0 inside
    out = []
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        if s[i] >= 0.0:
            out.append(poly[i])
        if (s[i] >= 0.0) != (s[j] >= 0.0):
            t = s[i] / (s[i] - s[j])
            out.append(poly[i] + t * (poly[j] - poly[i]))
    return _dedupe(np.array(out)) if out else np.empty((0, 2))


def grid_cells(model: WindshieldModel = DEFAULT_WINDSHIELD, n_u: int = DEFAULT_GRID[0],
               n_v: int = DEFAULT_GRID[1], arc_step: float = 0.005, min_area: float = 1e-6
               ) -> list[np.ndarray]:
    """Convex cells (K, 2) [m] in (u, v): an ``n_u`` x ``n_v`` grid over the outline's
    bounding box, each clipped to :func:`outline_polygon`; cells under ``min_area`` [m^2] are
    dropped. Ordered row by row (v), left to right (u) within a row.
    """
    if n_u < 1 or n_v < 1:
        raise ValueError(f"grid {n_u} x {n_v} must have at least one cell")
    outline = outline_polygon(model, arc_step)
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    us, vs = np.linspace(lo[0], hi[0], n_u + 1), np.linspace(lo[1], hi[1], n_v + 1)
    cells = []
    for j in range(n_v):
        for i in range(n_u):
            cell = outline
            for axis, bound, below in ((0, us[i], False), (0, us[i + 1], True),
                                       (1, vs[j], False), (1, vs[j + 1], True)):
                cell = _clip(cell, axis, bound, below)
            if len(cell) >= 3 and _signed_area(cell) > min_area:
                cells.append(cell)
    return cells


def build_piece(model: WindshieldModel, cell_uv: np.ndarray, resolution: float = 0.04,
                frame: str = "local") -> trimesh.Trimesh:
    """Closed slab of the glass over the convex cell ``cell_uv`` (K, 2) [m], counter-clockwise.

    Triangulated like :func:`ur_glue_planner.scene.windshield.build_mesh`: the cell's edges split
    into pieces of at most ``resolution`` [m], rings shrinking to the centroid; the bottom is
    the top moved by ``thickness`` along the inward normal, and a wall joins the two rims.
    """
    if not resolution > 0.0:
        raise ValueError(f"resolution {resolution} m must be > 0")
    cell = np.asarray(cell_uv, dtype=float)
    boundary = []
    for a, b in zip(cell, np.roll(cell, -1, axis=0)):
        k = max(1, math.ceil(np.linalg.norm(b - a) / resolution))
        boundary.append(a + np.arange(k)[:, None] / k * (b - a))
    boundary = np.vstack(boundary)
    uv, top_faces, side = fan_slab(boundary, resolution, min_rings=1)
    top = model.surface_point(uv[:, 0], uv[:, 1], frame)
    bottom = top - model.thickness * model.surface_normal(uv[:, 0], uv[:, 1], frame)
    all_faces = np.vstack([top_faces, top_faces[:, ::-1] + len(uv), side])
    return trimesh.Trimesh(vertices=np.vstack([top, bottom]), faces=all_faces, process=True)


def split_panel(model: WindshieldModel = DEFAULT_WINDSHIELD, n_u: int = DEFAULT_GRID[0],
                n_v: int = DEFAULT_GRID[1], resolution: float = 0.04, frame: str = "local"
                ) -> list[Piece]:
    """The glass cut into convex pieces (see :func:`grid_cells`, :func:`build_piece`)."""
    return [Piece(cell, build_piece(model, cell, resolution, frame))
            for cell in grid_cells(model, n_u, n_v)]


# ---------------------------------------------------------------------- hulls and deviation
def convex_hulls(meshes: list[trimesh.Trimesh]) -> list[trimesh.Trimesh]:
    """The convex hulls MuJoCo collides with, one per mesh, in the meshes' own frame.

    Each mesh is compiled (vertices only) into one MuJoCo model; its hull graph gives the hull
    faces. (trimesh's own hull needs scipy, which the project does not ship.)
    """
    import mujoco  # only needed here; keeps the planner importable without it

    def fmt(a: np.ndarray) -> str:
        return " ".join(f"{x:.9g}" for x in np.ravel(a))

    assets = "".join(f'<mesh name="m{i}" vertex="{fmt(mesh.vertices)}"/>'
                     for i, mesh in enumerate(meshes))
    geoms = "".join(f'<geom type="mesh" mesh="m{i}"/>' for i in range(len(meshes)))
    xml = f"<mujoco><asset>{assets}</asset><worldbody>{geoms}</worldbody></mujoco>"
    mj = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(mj)
    mujoco.mj_kinematics(mj, data)
    hulls = []
    for g in range(mj.ngeom):
        k = mj.geom_dataid[g]
        verts = mj.mesh_vert[mj.mesh_vertadr[k]:mj.mesh_vertadr[k] + mj.mesh_vertnum[k]]
        verts = verts @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        graph = mj.mesh_graph[mj.mesh_graphadr[k]:]
        numvert, numface = int(graph[0]), int(graph[1])
        start = 2 + 3 * numvert + 3 * numface  # after edgeadr, globalid, edge_localid
        faces = graph[start:start + 3 * numface].reshape(-1, 3).copy()
        tri = verts[faces]
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        inward = np.einsum("ij,ij->i", normal, verts.mean(axis=0) - tri[:, 0]) > 0.0
        faces[inward] = faces[inward][:, ::-1]  # outward: the vertex mean is inside a hull
        hulls.append(trimesh.Trimesh(vertices=verts, faces=faces, process=True))
    return hulls


def hull_envelope(model: WindshieldModel, hulls: list[trimesh.Trimesh], uv: np.ndarray,
                  frame: str = "local") -> tuple[np.ndarray, np.ndarray]:
    """Highest hull top and lowest hull bottom (M,) [m] in the panel's w over points uv (M, 2).

    The vertical (w) line through each (u, v) is cut with every hull (given in ``frame``);
    nan where it misses them all.
    """
    uv = np.atleast_2d(np.asarray(uv, dtype=float))
    top, bottom = np.full(len(uv), -np.inf), np.full(len(uv), np.inf)
    rot = model.local_from_panel
    if frame == "world":
        rot = model.pose[:3, :3] @ rot
    elif frame != "local":
        raise ValueError(f"frame {frame!r} must be 'world' or 'local'")
    for hull in hulls:
        verts = np.asarray(hull.vertices)
        if frame == "world":
            verts = verts - model.pose[:3, 3]
        verts = verts @ rot  # panel coordinates
        normals = np.asarray(hull.face_normals) @ rot  # outward
        offsets = np.einsum("ij,ij->i", normals, verts[np.asarray(hull.faces)[:, 0]])
        lo, hi = verts[:, :2].min(axis=0), verts[:, :2].max(axis=0)
        sel = np.flatnonzero(np.all((uv >= lo - 1e-9) & (uv <= hi + 1e-9), axis=1))
        if not len(sel):
            continue
        # face f: n_u u + n_v v + n_w w <= d
        rest = offsets[None] - uv[sel] @ normals[:, :2].T  # (S, F): n_w w <= rest
        nw = normals[:, 2]
        up, down, flat = nw > 1e-12, nw < -1e-12, np.abs(nw) <= 1e-12
        t = (rest[:, up] / nw[up]).min(axis=1) if up.any() else np.full(len(sel), np.inf)
        b = (rest[:, down] / nw[down]).max(axis=1) if down.any() else np.full(len(sel), -np.inf)
        hit = t >= b
        if flat.any():
            hit &= np.all(rest[:, flat] >= -1e-12, axis=1)
        top[sel[hit]] = np.maximum(top[sel[hit]], t[hit])
        bottom[sel[hit]] = np.minimum(bottom[sel[hit]], b[hit])
    missed = ~np.isfinite(top)
    top[missed], bottom[missed] = np.nan, np.nan
    return top, bottom


def sample_uv(model: WindshieldModel = DEFAULT_WINDSHIELD, step: float = 0.002,
              inset: float = 0.0) -> np.ndarray:
    """Grid points (M, 2) [m] ``step`` apart in (u, v), at least ``inset`` inside the edge."""
    outline = model.glass.sample(64)
    lo, hi = outline.min(axis=0), outline.max(axis=0)
    u, v = np.meshgrid(np.arange(lo[0], hi[0] + step, step), np.arange(lo[1], hi[1] + step, step))
    uv = np.column_stack([u.ravel(), v.ravel()])
    return uv[model.edge_distance(uv) >= inset]


def hull_deviation(model: WindshieldModel, hulls: list[trimesh.Trimesh], step: float = 0.002,
                   frame: str = "local") -> tuple[float, float]:
    """(max height of the hulls above the glue face, max depth below the back face) [m], in w.

    Over a ``step`` [m] grid inside the glass outline; the back face lies
    ``thickness / n_w`` below the glue face in w (n_w: the normal's w component).
    """
    uv = sample_uv(model, step)
    top, bottom = hull_envelope(model, hulls, uv, frame)
    f = model.height(uv[:, 0], uv[:, 1])
    n_w = model.surface_normal(uv[:, 0], uv[:, 1], "local") @ model.local_from_panel[:, 2]
    return float(np.nanmax(top - f)), float(np.nanmax((f - model.thickness / n_w) - bottom))


# ---------------------------------------------------------------------- files
def piece_name(index: int) -> str:
    """Body and file stem of piece ``index``: ``windshield_piece_XX``."""
    return f"windshield_piece_{index:02d}"


def write_pieces(out_dir: str | Path = "meshes", model: WindshieldModel = DEFAULT_WINDSHIELD,
                 n_u: int = DEFAULT_GRID[0], n_v: int = DEFAULT_GRID[1], resolution: float = 0.04,
                 max_deviation: float = MAX_DEVIATION) -> list[Path]:
    """Write the pieces as binary STL [m], LOCAL frame, ``<out_dir>/windshield_piece_XX.stl``.

    Stale ``windshield_piece_*.stl`` files in ``out_dir`` are removed first.

    Raises:
        ValueError: a hull rises more than ``max_deviation`` [m] above the glue face.
    """
    pieces = split_panel(model, n_u, n_v, resolution, "local")
    above, _ = hull_deviation(model, convex_hulls([p.mesh for p in pieces]))
    if above > max_deviation:
        raise ValueError(f"grid {n_u} x {n_v}: hulls rise {above * 1e3:.3f} mm above the glass "
                         f"(limit {max_deviation * 1e3:.3f} mm); use more tiles")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    for stale in out_dir.glob("windshield_piece_*.stl"):
        stale.unlink()
    paths = []
    for i, piece in enumerate(pieces):
        path = out_dir / f"{piece_name(i)}.stl"
        piece.mesh.export(str(path), file_type="stl")
        paths.append(path)
    return paths


def generate_default_pieces(out_dir: str | Path = "meshes") -> list[Path]:
    """Write the default windshield's pieces to ``out_dir`` (meshes/windshield_piece_XX.stl)."""
    return write_pieces(out_dir, DEFAULT_WINDSHIELD)
