"""ur_common.quaternions: (w, x, y, z), w >= 0, the conversions both packages use."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ur_common.quaternions import matrix_from_quat, quat_from_matrix, quat_normalize


def test_matrices_and_quaternions_round_trip_with_a_non_negative_w():
    mats = Rotation.random(200, random_state=3).as_matrix()
    q = quat_from_matrix(mats)
    assert q.shape == (200, 4) and np.all(q[:, 0] >= 0.0)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(matrix_from_quat(q), mats, atol=1e-12)


def test_a_quarter_turn_about_z_is_written_scalar_first():
    q = quat_from_matrix(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    np.testing.assert_allclose(q, [np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)], atol=1e-12)


def test_normalising_scales_and_picks_the_sign():
    np.testing.assert_allclose(quat_normalize(np.array([-2.0, 0.0, 0.0, 0.0])), [1.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match='zero norm'):
        quat_normalize(np.zeros(4))
