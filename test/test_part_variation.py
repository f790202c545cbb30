"""Generated windshields: reproducible from the seed, within every limit, and only the simulator's scene changes."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
import yaml

from ur_glue_planner.scene.part_scene import write_part_scene
from ur_glue_planner.scene.part_variation import (
    SAMPLE_STEP,
    VariationLimits,
    glass_center,
    make_part,
    placement_matrix,
)
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD
from ur_glue_planner.scene.windshield_pieces import MAX_DEVIATION, hull_deviation, sample_uv
from ur_sim_driver.description.scene import read_scene

UV = sample_uv(DEFAULT_WINDSHIELD, SAMPLE_STEP)  # the glass, every 10 mm, as the generator samples it


def test_same_seed_same_part_and_parts_differ() -> None:
    a, b, c = (make_part(DEFAULT_WINDSHIELD, 1, i) for i in (3, 3, 4))
    assert a.model == b.model and a.describe() == b.describe()
    assert a.offset != c.offset and a.model != c.model
    assert make_part(DEFAULT_WINDSHIELD, 2, 3).offset != a.offset


@pytest.mark.parametrize('limits', [VariationLimits(), VariationLimits(0.001, 0.2, 0.0005)])
def test_every_part_stays_within_its_limits(limits: VariationLimits) -> None:
    centre = glass_center(DEFAULT_WINDSHIELD)
    amplitudes = []
    for index in range(20):
        part = make_part(DEFAULT_WINDSHIELD, 7, index, limits)
        assert np.all(np.abs(part.offset) <= limits.placement)
        assert np.all(np.abs(part.rotation_deg) <= limits.rotation_deg)
        deviation = part.deviation(UV)
        assert np.abs(deviation).max() == pytest.approx(part.shape_amplitude, rel=0.02, abs=1e-7)
        assert part.shape_amplitude <= limits.shape
        amplitudes.append(part.shape_amplitude)
        # the glass centre moves by the offset alone (the rotation turns about it)
        moved = part.placement @ np.r_[centre, 1.0]
        assert moved[:3] - centre == pytest.approx(np.array(part.offset), abs=1e-12)
    assert max(amplitudes) > 0.5 * limits.shape  # the limit is used, not a sliver of it


def test_a_part_without_variation_is_the_nominal_glass() -> None:
    part = make_part(DEFAULT_WINDSHIELD, 1, 0, VariationLimits(0.0, 0.0, 0.0))
    points = DEFAULT_WINDSHIELD.surface_point(UV[:, 0], UV[:, 1])
    assert part.on_part(points) == pytest.approx(points, abs=1e-12)


def test_on_part_keeps_panel_coordinates_and_height() -> None:
    part = make_part(DEFAULT_WINDSHIELD, 1, 5)
    uv = UV[::40]
    above = DEFAULT_WINDSHIELD.surface_point(uv[:, 0], uv[:, 1]) + 0.003 * DEFAULT_WINDSHIELD.surface_normal(
        uv[:, 0], uv[:, 1])
    moved = part.on_part(above)
    back_uv, foot, normal = part.model.project(moved)
    assert back_uv == pytest.approx(uv, abs=1e-9)
    assert np.einsum('ij,ij->i', moved - foot, normal) == pytest.approx(0.003, abs=1e-9)


def test_placement_turns_about_the_pivot() -> None:
    pivot = np.array([0.1, 0.5, 0.2])
    t = placement_matrix(np.zeros(3), np.array([0.0, 0.0, 90.0]), pivot)
    assert (t @ np.r_[pivot, 1.0])[:3] == pytest.approx(pivot)
    assert (t @ np.r_[pivot + [0.1, 0, 0], 1.0])[:3] == pytest.approx(pivot + [0.0, 0.1, 0.0])


def test_limits_out_of_range_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match=r'placement = 0.5 is outside \[0, 0.05\]'):
        VariationLimits(placement=0.5)
    with pytest.raises(ValueError, match='shape'):
        VariationLimits(shape=-0.001)


def test_the_part_scene_places_the_generated_glass(tmp_path) -> None:
    part = make_part(DEFAULT_WINDSHIELD, 1, 2)
    scene = write_part_scene(part, tmp_path / 'part')
    bodies, scanners = read_scene(str(scene))
    names = [b[0] for b in bodies]
    assert names[0] == 'windshield' and len([n for n in names if n.startswith('windshield_piece_')]) >= 24
    for _, mesh, pose, _ in bodies:
        assert pose == pytest.approx(part.model.pose, abs=1e-9) and mesh.is_file()
    # the scanners are the cell's: the same as over the nominal glass
    assert scanners == read_scene('windshield')[1]
    # the meshes are relative to the scene file: the folder can move
    spec = yaml.safe_load(scene.read_text())
    assert all(not b['mesh'].startswith('/') for b in spec['bodies'])


def test_a_strongly_bent_part_gets_finer_collision_pieces(tmp_path) -> None:
    # part 18 of series 1 bends 1.73 mm: the nominal 12 x 2 tiles' hulls would stand 0.8 mm above its glass
    part = make_part(DEFAULT_WINDSHIELD, 1, 18)
    bodies, _ = read_scene(str(write_part_scene(part, tmp_path / 'part')))
    hulls = [trimesh.load(str(mesh)) for name, mesh, _, _ in bodies if name != 'windshield']  # the glass's frame
    above, _ = hull_deviation(part.model, hulls)
    assert len(hulls) > 24 and above <= MAX_DEVIATION
