"""The cell's part scanners: their layout, their scene block, their beams on the glass, their cloud over DDS."""
from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from sensor_msgs.msg import PointCloud2
from sim_harness import running_sim, wait_for
from test_io_and_status import Latest

from ur_common.paths import config_dir
from ur_glue_planner.scene.scanner_layout import INSIDE, OUTSIDE, POINTS, STANDOFF, scanner_layout
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD
from ur_sim_driver.description.part_scan import from_cloud, parse_scanners, to_cloud
from ur_sim_driver.description.scene import read_scene
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.physics.ray_scan import PartRays, measure

HOME = [0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0]


def nominal_rays():
    bodies, setup = read_scene('windshield')
    return PartRays([(n, m, p) for n, m, p, _ in bodies if n in setup.targets]), setup


def test_the_scene_file_holds_the_layout() -> None:
    spec = yaml.safe_load((config_dir() / 'scenes' / 'windshield.yaml').read_text())
    assert parse_scanners(spec['scanners']) == parse_scanners(scanner_layout())


def test_each_line_crosses_an_edge_and_lies_on_the_glass_inside_it() -> None:
    rays, setup = nominal_rays()
    assert len(setup.units) == 8
    spacing = (INSIDE + OUTSIDE) / (POINTS - 1)
    for unit in setup.units:
        beams, ranges = rays.profile(unit, setup.max_range)
        hit = np.isfinite(ranges)
        first = int(np.argmax(hit))
        # the misses come first (outside the edge), then only hits: one edge, seen from outside
        assert not hit[:first].any() and hit[first:].all(), unit.name
        assert first == pytest.approx(OUTSIDE / spacing, abs=2.0), unit.name
        points = np.asarray(unit.origin) + ranges[hit, None] * beams[hit]
        uv, foot, _ = DEFAULT_WINDSHIELD.project(points)
        # on the glue face (the mesh's chords leave 0.03 mm), and the first hit at the edge
        assert np.linalg.norm(points - foot, axis=1).max() < 5e-5, unit.name
        assert DEFAULT_WINDSHIELD.edge_distance(uv[0]) == pytest.approx(0.0, abs=1.5 * spacing), unit.name
        assert ranges[hit].min() == pytest.approx(STANDOFF, abs=0.005)


def test_noise_is_along_the_beam_and_as_large_as_set() -> None:
    rays, setup = nominal_rays()
    unit = setup.units[0]
    beams, ranges = rays.profile(unit, setup.max_range)
    rng = np.random.default_rng(0)
    noisy = np.stack([measure(np.asarray(unit.origin), beams, ranges, 1e-4, rng) for _ in range(50)])
    exact = measure(np.asarray(unit.origin), beams, ranges, 0.0, rng)
    hit = np.isfinite(ranges)
    error = noisy[:, hit] - exact[hit]
    along = np.einsum('kij,ij->ki', error, beams[hit])
    assert np.std(along) == pytest.approx(1e-4, rel=0.05)
    assert np.linalg.norm(error - along[..., None] * beams[hit], axis=2).max() < 1e-12
    assert np.isnan(noisy[:, ~hit]).all()


def test_cloud_round_trip_keeps_rows_and_misses() -> None:
    from builtin_interfaces.msg import Time

    points = np.arange(2 * 5 * 3, dtype=float).reshape(2, 5, 3) * 0.01
    points[0, :2] = np.nan
    msg = to_cloud(points, 'base_link', Time(sec=3))
    assert (msg.height, msg.width, msg.is_dense) == (2, 5, False)
    back = from_cloud(msg)
    assert np.isnan(back[0, :2]).all() and back[~np.isnan(back)] == pytest.approx(points[~np.isnan(points)], abs=1e-6)


@pytest.mark.parametrize('change, message', [
    ({'targets': []}, r'targets = \[\] must be a list of body names'),
    ({'noise': 0.5}, r'noise = 0.5 is outside'),
    ({'units': [{'name': 'a', 'origin': [0, 0, 1], 'direction': [0, 0, -1], 'line': [0, 0, 1], 'fov_deg': 10,
                 'points': 10}]}, 'line must be perpendicular to direction'),
    ({'units': [{'name': 'a', 'origin': [0, 0, 1], 'direction': [0, 0, -2], 'line': [1, 0, 0], 'fov_deg': 10,
                 'points': 10}]}, r'direction = \[0, 0, -2\] must be a unit vector'),
    ({'units': [{'name': 'a', 'origin': [0, 0, 1], 'direction': [0, 0, -1], 'line': [1, 0, 0], 'fov_deg': 10,
                 'points': 1}]}, r'points = 1 must be an integer in \[2, 4096\]'),
    ({'color': 'red'}, "must be a mapping with 'targets' and 'units'"),
])
def test_a_bad_scanner_block_is_refused_by_field(change: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_scanners({**scanner_layout(), **change})


def test_a_scene_that_is_neither_a_name_nor_a_file_is_refused_with_the_choices() -> None:
    with pytest.raises(ConfigError, match=r"scene 'windscreen' is unknown; valid choices: empty, windshield"):
        read_scene('windscreen')


def test_ur_sim_publishes_the_scan_in_base_link() -> None:
    with running_sim(ur_type='ur5', tool='dispenser', scene='windshield', initial_positions=HOME) as h:
        scans = Latest(h)
        h.listen(PointCloud2, '/ur_sim/part_scan', scans, latched=True)
        wait_for(lambda: len(scans.items) >= 2, what='two part scans')
        (a, _), (b, _) = scans.items[:2]
        assert a.header.frame_id == 'base_link' and (a.height, a.width) == (8, 400)
        pa, pb = from_cloud(a), from_cloud(b)
        hit = np.isfinite(pa).all(axis=2)
        assert hit.sum() > 8 * 250 and np.array_equal(hit, np.isfinite(pb).all(axis=2))
        assert not np.array_equal(pa[hit], pb[hit])  # fresh noise in each measurement
        # 5 Hz of simulated time
        dt = (b.header.stamp.sec - a.header.stamp.sec) + 1e-9 * (b.header.stamp.nanosec - a.header.stamp.nanosec)
        assert dt == pytest.approx(0.2, abs=h.sim.sim.control_dt + 1e-9)
        _, foot, _ = DEFAULT_WINDSHIELD.project(pa[hit])
        assert np.abs(np.linalg.norm(pa[hit] - foot, axis=1)).max() < 1e-3  # base_link = the planner's world
