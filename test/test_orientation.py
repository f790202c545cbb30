"""Rotation helpers: ZYX Euler angles to a matrix and back."""
import math

import numpy as np
import pytest

from ur_glue_planner.orientation import rotation_from_zyx_euler, zyx_euler_from_rotation


def test_zyx_angles_round_trip():
    rng = np.random.default_rng(1)
    for z, y, x in rng.uniform([-math.pi, -1.5, -math.pi], [math.pi, 1.5, math.pi], (200, 3)):
        back = zyx_euler_from_rotation(rotation_from_zyx_euler(z, y, x))
        assert back == pytest.approx((z, y, x), abs=1e-12)


@pytest.mark.parametrize('y', [math.pi / 2, -math.pi / 2])
def test_gimbal_lock_gives_the_same_rotation(y):
    r = rotation_from_zyx_euler(0.3, y, -0.7)
    assert np.allclose(rotation_from_zyx_euler(*zyx_euler_from_rotation(r)), r, atol=1e-12)
