"""The bead dataclass: PointCloud2 round trip and drawing into a MuJoCo scene."""
from __future__ import annotations

import os

import mujoco
import numpy as np
import pytest
from builtin_interfaces.msg import Time
from sensor_msgs.msg import PointField

from ur_sim_driver.description.bead import BASE_IN_WORLD, CLOUD_DTYPE, Bead, draw_bead, from_cloud, to_cloud

RGBA = (1.0, 0.0, 1.0, 1.0)  # magenta: no other geom of the test scene has it


def _bead(n: int = 50) -> Bead:
    s = np.linspace(0.0, 0.2, n)
    points = np.stack([s - 0.1, np.full(n, 0.05), 0.02 + 0.001 * np.sin(20 * s)], axis=1)
    return Bead(points, np.linspace(0.008, 0.012, n), np.linspace(0.0096, 0.0144, n), 10.0 + s / 0.15)


def test_round_trip_through_pointcloud2() -> None:
    bead = _bead()
    msg = to_cloud(bead, 'base', Time(sec=3, nanosec=5))
    assert msg.header.frame_id == 'base' and msg.header.stamp.sec == 3
    assert [f.name for f in msg.fields] == ['x', 'y', 'z', 'width', 'height', 't']
    assert [f.datatype for f in msg.fields] == [PointField.FLOAT32] * 5 + [PointField.FLOAT64]
    assert (msg.width, msg.height, msg.point_step) == (50, 1, 28) and len(msg.data) == 50 * 28
    back = from_cloud(msg)
    np.testing.assert_allclose(back.points, bead.points, atol=1e-7)  # float32 on the wire
    np.testing.assert_allclose(back.widths, bead.widths, rtol=1e-6)
    np.testing.assert_allclose(back.heights, bead.heights, rtol=1e-6)
    np.testing.assert_array_equal(back.times, bead.times)  # float64: exact


def test_times_go_on_the_clock_of_the_stamps() -> None:
    # In real time ur_sim's stamps count from the system clock: a deposit's t must be comparable with them.
    bead = _bead(5)
    origin = 1_795_000_000.25  # [s]
    back = from_cloud(to_cloud(bead, 'base', Time(sec=1_795_000_010), t_offset=origin))
    np.testing.assert_allclose(back.times - origin, bead.times, atol=1e-6)  # float64 near 1.8e9 s: 0.24 us


def test_empty_bead_round_trips() -> None:
    back = from_cloud(to_cloud(Bead.empty(), 'base', Time()))
    assert len(back) == 0 and back.points.shape == (0, 3)


def test_from_cloud_finds_fields_by_name_with_padding() -> None:
    # Another writer's layout: t first, then padding, then the rest in another order.
    dtype = np.dtype({'names': ['t', 'width', 'height', 'x', 'y', 'z'],
                      'formats': ['<f8', '<f4', '<f4', '<f4', '<f4', '<f4'],
                      'offsets': [0, 12, 16, 20, 24, 28], 'itemsize': 36})
    rows = np.zeros(3, dtype=dtype)
    rows['t'], rows['x'], rows['width'] = [1.0, 2.0, 3.0], [0.1, 0.2, 0.3], [0.01, 0.02, 0.03]
    msg = to_cloud(Bead.empty(), 'base', Time())
    msg.fields = [PointField(name=n, offset=dtype.fields[n][1], count=1,
                             datatype=PointField.FLOAT64 if n == 't' else PointField.FLOAT32) for n in dtype.names]
    msg.width, msg.point_step, msg.row_step, msg.data = 3, 36, 108, rows.tobytes()
    back = from_cloud(msg)
    np.testing.assert_allclose(back.points[:, 0], [0.1, 0.2, 0.3], rtol=1e-6)
    np.testing.assert_allclose(back.widths, [0.01, 0.02, 0.03], rtol=1e-6)
    np.testing.assert_array_equal(back.times, [1.0, 2.0, 3.0])


def test_from_cloud_names_a_missing_field() -> None:
    msg = to_cloud(_bead(3), 'base', Time())
    msg.fields = [f for f in msg.fields if f.name != 'width']
    with pytest.raises(ValueError, match="no field 'width'"):
        from_cloud(msg)


def test_bead_checks_shapes() -> None:
    with pytest.raises(ValueError, match=r'widths must have shape \(2,\)'):
        Bead(np.zeros((2, 3)), np.zeros(3), np.zeros(2), np.zeros(2))
    assert CLOUD_DTYPE.itemsize == 28


_XML = """
<mujoco>
  <visual><global offwidth="160" offheight="120"/></visual>
  <worldbody>
    <light pos="0 0 2" dir="0 0 -1" directional="true"/>
    <geom type="plane" size="1 1 0.1" rgba="0.5 0.5 0.5 1"/>
  </worldbody>
</mujoco>
"""


def _magenta(image: np.ndarray) -> int:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return int(np.count_nonzero((r > 120) & (b > 120) & (g < 60)))


def test_draw_bead_adds_capsules_and_renders_them() -> None:
    os.environ.setdefault('MUJOCO_GL', 'egl')
    model = mujoco.MjModel.from_xml_string(_XML)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    camera = mujoco.MjvCamera()
    camera.lookat[:] = (0.0, 0.05, 0.0)
    camera.distance, camera.azimuth, camera.elevation = 0.5, 90.0, -89.0
    with mujoco.Renderer(model, 120, 160) as renderer:
        renderer.update_scene(data, camera)
        before = renderer.scene.ngeom
        assert _magenta(renderer.render()) == 0
        renderer.update_scene(data, camera)
        bead = _bead()
        # Given in ur_sim's base frame: the drawing must turn it into the world (x, y negated).
        base_bead = Bead(bead.points * [-1.0, -1.0, 1.0], bead.widths, bead.heights, bead.times)
        added = draw_bead(renderer.scene, base_bead, RGBA, BASE_IN_WORLD)
        assert added == len(bead) - 1 and renderer.scene.ngeom == before + added
        g = renderer.scene.geoms[renderer.scene.ngeom - 1]
        np.testing.assert_allclose(g.pos, (bead.points[-2] + bead.points[-1]) / 2, atol=1e-6)
        image = renderer.render()
    # Seen from 0.5 m (fovy 45 deg: 120 px span 0.41 m, 290 px/m) the 20 cm x 1 cm bead covers ~170 px.
    assert _magenta(image) > 100


def test_draw_bead_keeps_within_the_geom_budget_and_leaves_gaps() -> None:
    model = mujoco.MjModel.from_xml_string(_XML)
    scene = mujoco.MjvScene(model, maxgeom=30)
    bead = _bead(100)
    assert draw_bead(scene, bead, RGBA) <= 30 and scene.ngeom <= 30
    scene = mujoco.MjvScene(model, maxgeom=100)
    points = bead.points.copy()
    points[50:] += [0.0, 0.1, 0.0]  # a 10 cm gap between two runs
    assert draw_bead(scene, Bead(points, bead.widths, bead.heights, bead.times), RGBA) == 98
