"""Our windshield: fits the seed's clicked waypoints, closed mesh, seed placement."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from ur_glue_planner.defaults import DEFAULT_WAYPOINTS
from ur_glue_planner.scene.windshield import (
    DEFAULT_WINDSHIELD,
    build_mesh,
    local_to_world,
    seed_pose,
    windshield_pose,
    world_to_local,
    write_stl,
)

STL = Path(__file__).resolve().parents[1] / "meshes" / "windshield.stl"


def mesh_distance(mesh: trimesh.Trimesh, points: np.ndarray) -> np.ndarray:
    """Distance (M,) [m] from points to the closest point on the mesh (brute force).

    trimesh.proximity needs rtree, which the project does not ship; all triangles per point
    is fast enough at a few thousand faces.
    """
    tri = mesh.triangles
    return np.array([np.linalg.norm(trimesh.triangles.closest_point(
        tri, np.broadcast_to(p, (len(tri), 3))) - p, axis=1).min() for p in points])


@pytest.fixture(scope="module")
def world_mesh() -> trimesh.Trimesh:
    return build_mesh(DEFAULT_WINDSHIELD, frame="world")


def test_every_default_waypoint_lies_on_the_mesh(world_mesh):
    d = mesh_distance(world_mesh, DEFAULT_WAYPOINTS)
    assert d.max() < 0.003, f"waypoint {d.argmax()} is {d.max() * 1e3:.2f} mm off the mesh"


def test_waypoints_lie_on_the_glue_face_inside_the_glass():
    uv, foot, normal = DEFAULT_WINDSHIELD.project(DEFAULT_WAYPOINTS)
    assert np.linalg.norm(foot - DEFAULT_WAYPOINTS, axis=1).max() < 0.001
    assert np.all(normal[:, 2] > 0.9)  # the glue face looks up in the world
    # the bead runs some cm inside the glass edge
    assert DEFAULT_WINDSHIELD.edge_distance(uv).min() > 0.02


def test_committed_stl_is_the_local_frame_mesh_and_small():
    assert STL.stat().st_size < 1_000_000
    mesh = trimesh.load(str(STL), file_type="stl")
    assert mesh.is_watertight
    expected = build_mesh(DEFAULT_WINDSHIELD, frame="local")
    np.testing.assert_allclose(mesh.bounds, expected.bounds, atol=1e-6)
    placed = mesh.copy().apply_transform(windshield_pose())
    assert mesh_distance(placed, DEFAULT_WAYPOINTS).max() < 0.003


def test_write_stl_round_trip(tmp_path):
    path = write_stl(tmp_path / "glass.stl", resolution=0.08, frame="world")
    mesh = trimesh.load(str(path), file_type="stl")
    assert mesh.is_watertight and mesh.volume > 0


def test_mesh_is_watertight_with_outward_normals(world_mesh):
    assert world_mesh.is_watertight
    assert world_mesh.is_winding_consistent
    assert world_mesh.volume > 0.0  # outward normals give a positive volume


def test_thickness_is_a_few_mm(world_mesh):
    # a thin plate has volume ~ thickness * area / 2 (the rim adds < 2 % area)
    estimate = 2.0 * world_mesh.volume / world_mesh.area
    assert 0.003 < estimate < 0.008
    assert estimate == pytest.approx(DEFAULT_WINDSHIELD.thickness, rel=0.05)


def test_glue_face_is_doubly_curved():
    m = DEFAULT_WINDSHIELD
    u, v, h = 0.0, 0.22, 1e-2
    n = m.surface_normal(u, v)
    # second differences of the world surface along u and v, measured along the normal
    ku = (m.surface_point(u + h, v) - 2 * m.surface_point(u, v) + m.surface_point(u - h, v)) @ n
    kv = (m.surface_point(u, v + h) - 2 * m.surface_point(u, v) + m.surface_point(u, v - h)) @ n
    assert abs(ku / h ** 2) > 0.1  # across the width: radius ~5 m
    assert abs(kv / h ** 2) > 0.01  # along the height: radius ~40 m
    k = m.principal_curvatures(np.array([-0.3, 0.0, 0.3]), np.array([0.05, 0.22, 0.4]))
    assert np.all(np.abs(k) > 0.01)
    assert k[1, 0] == pytest.approx(ku / h ** 2, rel=1e-3)


def test_local_and_world_transforms_invert_each_other():
    rng = np.random.default_rng(0)
    p = rng.uniform(-1.0, 1.0, (50, 3))
    np.testing.assert_allclose(world_to_local(local_to_world(p)), p, atol=1e-12)
    np.testing.assert_allclose(local_to_world(world_to_local(p)), p, atol=1e-12)
    pose = windshield_pose()
    np.testing.assert_allclose(local_to_world(p), p @ pose[:3, :3].T + pose[:3, 3], atol=1e-12)


def test_seed_transform_matches_matlab_row_vector_product():
    # MATLAB: [0.1 0.2 0.3] * rotationX(55) + [0 0.4 0.15], worked out by hand:
    # y' = 0.2 cos55 + 0.3 sin55, z' = -0.2 sin55 + 0.3 cos55
    c, s = math.cos(math.radians(55)), math.sin(math.radians(55))
    expected = [0.1, 0.4 + 0.2 * c + 0.3 * s, 0.15 - 0.2 * s + 0.3 * c]
    np.testing.assert_allclose(expected, [0.1, 0.7604608, 0.1582425], atol=1e-7)
    np.testing.assert_allclose(local_to_world(np.array([0.1, 0.2, 0.3])), expected, atol=1e-12)
    np.testing.assert_allclose(windshield_pose(), seed_pose(55.0, (0.0, 0.4, 0.15)))


def test_outline_is_inset_by_the_offset_and_follows_the_bead():
    m = DEFAULT_WINDSHIELD
    for offset in (0.0, 0.03):
        uv = m.outline_uv(offset, 400)
        np.testing.assert_allclose(m.edge_distance(uv), offset, atol=1e-9)
        steps = np.linalg.norm(np.diff(uv, axis=0), axis=1)
        assert steps.max() < 1.01 * steps.mean()  # equal arc-length spacing
    bead = m.outline(0.03, 400)
    _, foot, _ = m.project(bead)
    np.testing.assert_allclose(foot, bead, atol=1e-9)  # on the glue face
    # starts at the bottom-left going up the left edge, like the seed's bead
    assert bead[0, 0] < -0.3 and bead[1, 1] > bead[0, 1]
    gaps = [np.linalg.norm(bead - p, axis=1).min() for p in DEFAULT_WAYPOINTS]
    assert max(gaps) < 0.025


def test_project_recovers_points_above_the_face():
    m = DEFAULT_WINDSHIELD
    u, v = np.array([-0.3, 0.0, 0.25]), np.array([0.02, 0.2, 0.41])
    p = m.surface_point(u, v) + 0.02 * m.surface_normal(u, v)
    uv, foot, _ = m.project(p)
    np.testing.assert_allclose(uv, np.column_stack([u, v]), atol=1e-10)
    np.testing.assert_allclose(foot, m.surface_point(u, v), atol=1e-10)
