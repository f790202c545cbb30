"""Convex collision pieces of the windshield: hulls hug the glass, cover it, and MuJoCo agrees."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
import yaml

from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD, windshield_pose
from ur_glue_planner.scene.windshield_pieces import (
    MAX_DEVIATION,
    convex_hulls,
    grid_cells,
    hull_deviation,
    hull_envelope,
    outline_polygon,
    piece_name,
    sample_uv,
    split_panel,
    write_pieces,
)
from ur_sim_driver.description.mjcf import add_static_mesh, build_mjcf
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.scene import load_scene
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
MESHES = ROOT / "meshes"
HOME = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])
M = DEFAULT_WINDSHIELD
PROBE_RADIUS = 0.001  # [m]


def piece_files() -> list[Path]:
    return sorted(MESHES.glob("windshield_piece_*.stl"))


def polygon_area(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))


@pytest.fixture(scope="module")
def pieces() -> list[trimesh.Trimesh]:
    return [trimesh.load(str(p), file_type="stl") for p in piece_files()]


@pytest.fixture(scope="module")
def hulls(pieces) -> list[trimesh.Trimesh]:
    return convex_hulls(pieces)


def scene_xml(*, whole_collides: bool | None = None, with_pieces: bool = True, probe: bool = False) -> str:
    """UR5 + dispenser + the windshield scene; ``whole_collides`` overrides the YAML's flag."""
    xml = build_mjcf(load_ur_params("ur5"), tool=get_tool("dispenser"))
    for name, mesh, pose, collide in load_scene("windshield"):
        if name == "windshield":
            xml = add_static_mesh(xml, name, mesh, pose,
                                  collide=collide if whole_collides is None else whole_collides)
        elif with_pieces:
            xml = add_static_mesh(xml, name, mesh, pose, collide=collide)
    if probe:  # a free 1 mm sphere that meets the environment (bits 3) only, not the robot (bit 1)
        xml = xml.replace("</worldbody>", f'<body name="probe"><freejoint name="probe"/>'
                          '<inertial pos="0 0 0" mass="0.001" diaginertia="1e-9 1e-9 1e-9"/>'
                          f'<geom name="probe" type="sphere" size="{PROBE_RADIUS}" contype="2" conaffinity="2"/>'
                          '</body></worldbody>')
    return xml


def probe_contacts(mj: mujoco.MjModel, data: mujoco.MjData, point: np.ndarray) -> set[str]:
    """Names of the geoms the probe touches when centred at ``point`` (world), arm at home."""
    adr = mj.jnt_qposadr[mj.joint("probe").id]
    data.qpos[:6] = HOME
    data.qpos[adr:adr + 7] = [*point, 1.0, 0.0, 0.0, 0.0]
    mujoco.mj_forward(mj, data)
    probe = mj.geom("probe").id
    return {mj.geom(c.geom2 if c.geom1 == probe else c.geom1).name
            for c in data.contact[:data.ncon] if probe in (c.geom1, c.geom2)}


# ---------------------------------------------------------------------- files and scene
def test_committed_pieces_are_the_generated_ones_and_small(pieces, tmp_path):
    files = piece_files()
    assert [p.stem for p in files] == [piece_name(i) for i in range(len(files))]
    assert 4 <= len(files) <= 64
    assert sum(p.stat().st_size for p in files) < 1_000_000
    generated = split_panel(M)
    assert len(generated) == len(pieces)
    for mesh, piece in zip(pieces, generated):
        np.testing.assert_allclose(mesh.bounds, piece.mesh.bounds, atol=1e-6)  # float32 STL
    # writing replaces stale pieces
    (tmp_path / "windshield_piece_99.stl").write_bytes(b"")
    written = write_pieces(tmp_path, n_u=10, n_v=2)
    assert sorted(tmp_path.glob("*.stl")) == written and len(written) == 20
    with pytest.raises(ValueError, match="above the glass"):
        write_pieces(tmp_path, n_u=3, n_v=1)


def test_scene_collides_with_the_pieces_and_shows_the_whole_mesh():
    bodies = load_scene("windshield")
    names = [b[0] for b in bodies]
    assert names == ["windshield", *(piece_name(i) for i in range(len(piece_files())))]
    for name, mesh, pose, collide in bodies:
        assert mesh == (MESHES / f"{name}.stl").resolve()
        np.testing.assert_allclose(pose, windshield_pose(), atol=1e-12)
        assert collide is (name != "windshield")
    mj = mujoco.MjModel.from_xml_string(scene_xml())
    whole = mj.geom("windshield")
    assert whole.contype == 0 and whole.conaffinity == 0
    assert all(mj.geom(n).contype == 3 and mj.geom(n).conaffinity == 3 for n in names[1:])


def test_scene_collide_key_must_be_boolean(tmp_path, monkeypatch):
    import ur_sim_driver.description.scene as scene

    (tmp_path / "config" / "scenes").mkdir(parents=True)
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "a.stl").write_bytes((MESHES / "windshield_piece_00.stl").read_bytes())
    body = {"name": "a", "mesh": "meshes/a.stl", "pose": {"xyz": [0, 0, 0], "rpy": [0, 0, 0]}}
    (tmp_path / "config" / "scenes" / "ok.yaml").write_text(yaml.safe_dump({"bodies": [body]}))
    (tmp_path / "config" / "scenes" / "bad.yaml").write_text(
        yaml.safe_dump({"bodies": [{**body, "collide": "no"}]}))
    monkeypatch.setattr(scene, "config_dir", lambda: tmp_path / "config")
    assert scene.load_scene("ok")[0][3] is True
    with pytest.raises(ConfigError, match="collide"):
        scene.load_scene("bad")


# ---------------------------------------------------------------------- geometry
def test_pieces_are_closed_convex_slabs(pieces, hulls):
    for i, (mesh, hull) in enumerate(zip(pieces, hulls)):
        assert mesh.is_watertight and mesh.is_winding_consistent, i
        assert mesh.volume > 0.0, i
        # the hull (MuJoCo's) holds every vertex, and the slab fills almost all of it
        plane = np.einsum("ij,ij->i", hull.face_normals, hull.triangles[:, 0])
        assert (mesh.vertices @ hull.face_normals.T - plane).max() < 1e-6, i
        assert hull.volume >= mesh.volume * (1 - 1e-6), i
        # convex-ish: the 5 mm slab fills > 90 % of its hull, the mean gap over the faces is < 0.5 mm
        assert mesh.volume > 0.9 * hull.volume, f"piece {i}: {mesh.volume / hull.volume:.3f} of its hull"
        assert hull.volume - mesh.volume < MAX_DEVIATION * mesh.area / 2, i


def test_hulls_hug_the_glass(hulls):
    above, below = hull_deviation(M, hulls, step=0.002)
    assert above <= MAX_DEVIATION, f"a hull rises {above * 1e3:.3f} mm above the glue face"
    assert below <= MAX_DEVIATION, f"a hull reaches {below * 1e3:.3f} mm below the back face"


def test_the_whole_panel_hull_would_float_above_the_glass():
    whole = trimesh.load(str(MESHES / "windshield.stl"), file_type="stl")
    above, _ = hull_deviation(M, convex_hulls([whole]), step=0.01)
    assert above > 0.01  # why the pieces exist


def test_pieces_cover_the_glass(hulls):
    cells = grid_cells(M)
    outline = outline_polygon(M)
    assert sum(polygon_area(c) for c in cells) == pytest.approx(polygon_area(outline), rel=1e-9)
    assert polygon_area(outline) == pytest.approx(polygon_area(M.glass.sample(4000)), rel=1e-4)
    uv = sample_uv(M, step=0.004, inset=0.0002)
    top, bottom = hull_envelope(M, hulls, uv)
    assert not np.isnan(top).any(), f"{np.isnan(top).sum()} glass points under no piece"
    f = M.height(uv[:, 0], uv[:, 1])
    assert (top - f).min() > -2e-5  # some piece reaches the glue face everywhere
    assert (f - bottom).min() > 0.95 * M.thickness  # and holds the full thickness below it


# ---------------------------------------------------------------------- MuJoCo
def test_arm_at_home_touches_nothing():
    mj = mujoco.MjModel.from_xml_string(scene_xml())
    data = mujoco.MjData(mj)
    data.qpos[:] = HOME
    mujoco.mj_forward(mj, data)
    assert data.ncon == 0, [(mj.geom(c.geom1).name, mj.geom(c.geom2).name) for c in data.contact[:data.ncon]]


def probe_uv() -> np.ndarray:
    """20 glass points: the centre line (a piece boundary), the middle row boundary, random ones."""
    v_mid = 0.5 * (outline_polygon(M)[:, 1].min() + outline_polygon(M)[:, 1].max())
    fixed = [(0.0, 0.1), (0.0, v_mid), (0.0, 0.4), (0.2, v_mid), (-0.3, v_mid)]
    rng = np.random.default_rng(7)
    lo, hi = M.glass.corners.min(axis=0), M.glass.corners.max(axis=0)
    candidates = rng.uniform(lo, hi, size=(400, 2))
    inside = candidates[M.edge_distance(candidates) > 0.01]
    return np.vstack([fixed, inside[:20 - len(fixed)]])


def test_probe_above_the_glass_is_free_and_inside_it_touches():
    mj = mujoco.MjModel.from_xml_string(scene_xml(probe=True))
    data = mujoco.MjData(mj)
    uv = probe_uv()
    assert len(uv) == 20
    points = M.surface_point(uv[:, 0], uv[:, 1], "world")
    normals = M.surface_normal(uv[:, 0], uv[:, 1], "world")
    for p, n in zip(points, normals):
        assert probe_contacts(mj, data, p + 0.003 * n) == set(), f"probe 3 mm above {p} touches"
        touched = probe_contacts(mj, data, p - 0.003 * n)
        assert touched and all(t.startswith("windshield_piece_") for t in touched), (p, touched)


def test_probe_would_hit_the_hull_of_the_whole_panel():
    """Regression guard: with the whole mesh colliding, the probe above the middle touches air."""
    mj = mujoco.MjModel.from_xml_string(scene_xml(whole_collides=True, with_pieces=False, probe=True))
    data = mujoco.MjData(mj)
    v_mid = 0.5 * (outline_polygon(M)[:, 1].min() + outline_polygon(M)[:, 1].max())
    p = M.surface_point(0.0, v_mid, "world") + 0.003 * M.surface_normal(0.0, v_mid, "world")
    assert probe_contacts(mj, data, p) == {"windshield"}
