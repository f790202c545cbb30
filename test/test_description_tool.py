"""The seed 1 glue dispenser tool definition."""

import math

import numpy as np
import pytest

from ur_sim_driver.description.tool import DISPENSER, TOOL_CHOICES, get_tool
from ur_sim_driver.errors import ConfigError


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def _trans(x, y, z):
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def test_choices():
    assert TOOL_CHOICES == ('none', 'dispenser')
    assert get_tool(None) is None and get_tool('none') is None and get_tool('') is None
    assert get_tool('dispenser') is DISPENSER and get_tool('Dispenser') is DISPENSER


@pytest.mark.parametrize('bad', ['gripper', 'dispensor', 7])
def test_unknown_tool_names_value_and_choices(bad):
    with pytest.raises(ConfigError) as err:
        get_tool(bad)
    assert repr(bad) in str(err.value) and 'none' in str(err.value) and 'dispenser' in str(err.value)


def test_tip_matches_seed_and_design():
    # Seed 1: dispenser = tool0 * Rx(-90 deg); dispenserEdge = dispenser * T(0.04, -0.195, 0) * Rx(180 deg).
    seed = _rx(-math.pi / 2) @ _trans(0.04, -0.195, 0.0) @ _rx(math.pi)
    # DESIGN.md section 6, composed form.
    design = _trans(0.04, 0.0, 0.195) @ _rx(math.pi / 2)
    np.testing.assert_allclose(seed, design, atol=1e-15)
    np.testing.assert_allclose(DISPENSER.tip_in_tool0(), design, atol=1e-15)
    assert DISPENSER.name == 'dispenser' and DISPENSER.tip_name == 'dispenser_tip'


def test_mass_and_geometry_are_plausible():
    t = DISPENSER
    assert 0.1 < t.mass < 2.0
    xx, xy, xz, yy, yz, zz = t.inertia
    assert min(np.linalg.eigvalsh([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])) > 0
    tip = t.tip.matrix()[:3, 3]
    for g in t.geoms:
        centre, axis = np.array(g.origin.xyz), g.origin.matrix()[:3, 2]
        for end in (centre + axis * g.length / 2, centre - axis * g.length / 2):
            # Geometry lies on the outward side of the flange (-y in the tool frame) and no
            # part of it reaches the tip itself.
            assert end[1] <= 1e-12 and np.linalg.norm(end - tip) > 0.005
