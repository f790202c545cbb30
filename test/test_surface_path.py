"""SurfacePath: the planned path laid onto the glass, the tip on the nozzle axis through each line point."""
import numpy as np
import pytest

from ur_glue_planner.job import parse_job
from ur_glue_planner.path.glue_path import build_glue_path
from ur_glue_planner.path.run_up import RunUpPath
from ur_glue_planner.path.surface_path import SurfacePath
from ur_glue_planner.scene.waypoints import job_waypoints, tool_axis
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD

AXIS = tuple(tool_axis('dispenser'))


@pytest.fixture(scope='module')
def chords():
    points, rots = job_waypoints(parse_job({}))
    return build_glue_path(points, rots, max_deviation=0.02, closed=True)


def height(p):
    _, foot, normal = DEFAULT_WINDSHIELD.project(p)
    return np.sum((p - foot) * normal, axis=1), foot


def test_chords_rise_above_the_glass_and_the_surface_path_does_not(chords):
    s = np.linspace(0.0, chords.length, 2000, endpoint=False)
    assert height(chords.sample(s)[0])[0].max() > 1.5e-3  # seed 1's sparse clicks on a concave glass
    surf = SurfacePath(chords, DEFAULT_WINDSHIELD, 0.0, AXIS)
    assert np.abs(height(surf.sample(s)[0])[0]).max() < 1e-6


@pytest.mark.parametrize('standoff', [0.0, 0.01])
def test_tangent_curvature_and_standoff_along_the_nozzle_axis(chords, standoff):
    surf = SurfacePath(chords, DEFAULT_WINDSHIELD, standoff, AXIS)
    s = np.linspace(0.0, chords.length, 500, endpoint=False)
    pos, tan, kappa = surf.sample(s)
    np.testing.assert_allclose(np.linalg.norm(tan, axis=1), 1.0, atol=1e-12)
    h = 1e-5  # the tangent against a finer chord of the projected points
    chord = (surf.sample(s + h)[0] - surf.sample(s - h)[0]) / (2 * h)
    err = np.abs(chord / np.linalg.norm(chord, axis=1, keepdims=True) - tan).max(axis=1)
    # kappa h / 2 where an arc meets a line (curvature jumps; the loop starts at one); 1e-6 elsewhere
    assert err.max() < 1e-3 and np.median(err) < 1e-6
    kvec = surf.curvature_vector(s)
    np.testing.assert_allclose(np.linalg.norm(kvec, axis=1), kappa)
    assert np.abs(np.sum(kvec * tan, axis=1)).max() < 1e-6 * max(1.0, kappa.max())
    # the tip stands `standoff` above the glass, and the nozzle axis through it meets the glass on the line
    hgt, _ = height(pos)
    np.testing.assert_allclose(hgt, standoff, atol=1e-6)
    axis = surf.orientation(s) @ np.array(AXIS)
    line = DEFAULT_WINDSHIELD.project(chords.sample(s)[0])[1]
    _, _, normal = DEFAULT_WINDSHIELD.project(line)
    t = np.sum((line - pos) * normal, axis=1) / np.sum(axis * normal, axis=1)  # ray to the line's tangent plane
    np.testing.assert_allclose(pos + t[:, None] * axis, line, atol=2e-5)


@pytest.mark.parametrize('standoff', [0.0, 0.01])
def test_derivatives_in_one_evaluation_equal_sample_and_curvature_vector(chords, standoff):
    surf = SurfacePath(chords, DEFAULT_WINDSHIELD, standoff, AXIS)
    s = np.linspace(0.0, chords.length, 300, endpoint=False)
    for path, x in ((chords, s), (surf, s), (RunUpPath(surf, 0.05, 0.04), s + 0.02)):
        pos, tan, kvec = path.derivatives(x)
        np.testing.assert_array_equal(pos, path.sample(x)[0])
        np.testing.assert_array_equal(tan, path.sample(x)[1])
        np.testing.assert_array_equal(kvec, path.curvature_vector(x))


def test_position_alone_equals_the_sampled_one(chords):
    surf = SurfacePath(chords, DEFAULT_WINDSHIELD, 0.003, AXIS)
    s = np.linspace(0.0, chords.length, 50, endpoint=False)
    for path, x in ((chords, s), (surf, s), (RunUpPath(surf, 0.05, 0.04), s + 0.02)):
        np.testing.assert_array_equal(path.position(x), path.sample(x)[0])
        np.testing.assert_array_equal(path.position(x[7]), path.sample(x[7])[0])
