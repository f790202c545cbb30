"""Picking points on the glue face: a click ray's hit, and a dragged point put back onto the glass."""
import numpy as np

from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD as GLASS
from ur_glue_planner.studio.surface_pick import onto_surface, ray_hit


def test_rays_from_any_side_hit_the_surface_point_they_aim_at():
    rng = np.random.default_rng(3)
    uv = np.column_stack([rng.uniform(-0.3, 0.3, 30), rng.uniform(0.0, 0.45, 30)])
    for u, v in uv:
        target = GLASS.surface_point(u, v)
        above = target + 0.8 * GLASS.surface_normal(u, v)
        for origin in (above, np.array([0.5, -0.6, 1.2]), np.array([0.0, 0.2, 2.0])):
            hit = ray_hit(GLASS, origin, target - origin)
            assert hit is not None
            assert np.linalg.norm(hit.position - target) < 1e-9
            assert np.allclose(hit.uv, [u, v], atol=1e-9)


def test_misses_are_none():
    assert ray_hit(GLASS, [0.0, 0.5, 1.0], [0.0, 0.0, 1.0]) is None  # pointing away
    assert ray_hit(GLASS, [2.0, 0.5, 1.0], [0.0, 0.0, -1.0]) is None  # beside the glass
    assert ray_hit(GLASS, [0.0, -3.0, 0.2], [1.0, 0.0, 0.0]) is None  # parallel, far below


def test_dragged_points_go_back_onto_the_glass_inside_its_outline():
    target = GLASS.surface_point(0.1, 0.2)
    normal = GLASS.surface_normal(0.1, 0.2)
    back = onto_surface(GLASS, target + 0.03 * normal)
    assert np.linalg.norm(back.position - target) < 1e-9
    assert onto_surface(GLASS, GLASS.surface_point(0.7, 0.2)) is None
