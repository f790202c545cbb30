"""The part as the scanners see it, fitted to the nominal glass; and the bead planned on what was found."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

from ur_glue_planner.execution.part_measure import measure_part
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.scene.part_variation import VariationLimits, make_part, move_onto
from ur_glue_planner.scene.registration import register, split_profiles
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD, write_stl
from ur_sim_driver.description.scene import read_scene
from ur_sim_driver.physics.ray_scan import PartRays, measure

SETUP = read_scene('windshield')[1]
HOME = np.array([0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0])


def scan(part, folder, seed: int = 0, noise: float | None = None) -> np.ndarray:
    """What the cell's scanners report over ``part``: profiles (8, 400, 3) [m], NaN where nothing was seen."""
    write_stl(folder / 'glass.stl', part.model, frame='local')
    rays = PartRays([('windshield', folder / 'glass.stl', part.model.pose)])
    rng = np.random.default_rng(seed)
    return np.stack([measure(np.asarray(u.origin), *rays.profile(u, SETUP.max_range),
                             SETUP.noise if noise is None else noise, rng) for u in SETUP.units])


@pytest.mark.parametrize('index', range(6))
def test_the_fit_finds_the_part_and_the_bead_line_on_it(index: int, tmp_path) -> None:
    part = make_part(DEFAULT_WINDSHIELD, 3, index)
    found = register(scan(part, tmp_path, seed=index), DEFAULT_WINDSHIELD)
    assert (found.face_points, found.edge_points) == (pytest.approx(8 * 300, rel=0.02), 8)
    # what it found: the placement to a fraction of a millimetre, the face to the scanners' noise
    assert found.offset[:2] == pytest.approx(np.array(part.offset[:2]), abs=3e-4)
    assert found.face_rms < 2.0 * SETUP.noise and found.edge_rms < 2e-4
    # the bead's line (30 mm inside the edge, where the lines look) moved onto the part as it is
    line = DEFAULT_WINDSHIELD.outline(0.03, 400)
    truth, moved = part.on_part(line), move_onto(line, DEFAULT_WINDSHIELD, found.model)
    assert np.linalg.norm(moved - truth, axis=1).max() < 3e-4
    assert np.linalg.norm(line - truth, axis=1).max() > 3e-3  # and the part was off by millimetres


def test_an_undisturbed_part_is_found_where_it_should_be(tmp_path) -> None:
    part = make_part(DEFAULT_WINDSHIELD, 1, 0, VariationLimits(0.0, 0.0, 0.0))
    found = register(scan(part, tmp_path, noise=0.0), DEFAULT_WINDSHIELD)
    assert np.abs(found.offset).max() < 1e-4 and np.abs(found.rotation_deg).max() < 0.01
    assert np.abs(found.shape).max() < 1e-4


def test_profiles_split_into_face_and_one_edge_each() -> None:
    row = np.full((10, 3), np.nan)
    row[4:] = np.column_stack([np.arange(4, 10) * 0.001, np.zeros(6), np.zeros(6)])
    no_edge = np.zeros((10, 3))  # hits from the first beam on: the edge is not in view
    face, edges = split_profiles(np.stack([row, no_edge, np.full((10, 3), np.nan)]))
    assert len(face) == 16 and edges == pytest.approx(np.array([[0.0035, 0.0, 0.0]]))


def test_too_little_seen_is_refused_with_what_was_seen() -> None:
    profiles = np.full((8, 400, 3), np.nan)
    with pytest.raises(ValueError, match='the scanners saw 0 glass edges and 0 points on the glass'):
        register(profiles, DEFAULT_WINDSHIELD)


def test_the_bead_is_planned_on_the_measured_part(tmp_path) -> None:
    job = load_job('config/glue_job.yaml')
    part = make_part(DEFAULT_WINDSHIELD, 3, 1)
    found = register(scan(part, tmp_path), DEFAULT_WINDSHIELD)
    nominal, corrected = plan_job(job, HOME), plan_job(job, HOME, part=found)
    assert corrected.part is found and corrected.surface is found.model
    truth = part.on_part(nominal.line)
    # the corrected plan's line lies where the nominal line lies on the real part; the nominal one does not
    assert np.linalg.norm(corrected.line - truth, axis=1).max() < 3e-4
    assert np.linalg.norm(nominal.line - truth, axis=1).max() > 3e-3
    # the tip follows it: the bead's tip positions on the measured glass
    tips = np.array([corrected.kinematics.fk(q)[:3, 3] for q in corrected.bead.q[::25]])
    _, foot, _ = found.model.project(tips)
    assert np.linalg.norm(tips - foot, axis=1).max() < 2e-4


def test_a_part_too_far_off_is_measured_and_refused(tmp_path) -> None:
    limits = VariationLimits(placement=0.015, rotation_deg=0.2, shape=0.0)
    index = next(i for i in range(20) if np.abs(make_part(DEFAULT_WINDSHIELD, 5, i, limits).offset).max() > 0.011)
    part = make_part(DEFAULT_WINDSHIELD, 5, index, limits)
    found, reason = measure_part(scan(part, tmp_path), DEFAULT_WINDSHIELD)
    axis = int(np.argmax(np.abs(part.offset)))
    assert found.offset[axis] == pytest.approx(part.offset[axis], abs=5e-4)
    assert reason is not None and re.fullmatch(rf'the part is [+-]\d+\.\d mm off along {"xyz"[axis]}, beyond the '
                                               r'10 mm the cell corrects', reason), reason
