"""The compiled packing of controller_state values against the numpy expression it replaced."""
import numpy as np
import pytest

from ur_sim_driver.controllers.controller_state import ARRAYS, FIELDS, pack_state


def _numpy(q_ref, qd_ref, qdd_ref, q, qd, q_cmd, factor):
    # error.velocities: 0.0 in a position-command configuration (upstream's compute_error_for_joint)
    return np.concatenate((q_ref, qd_ref, qdd_ref, q, qd, q_ref - q, np.zeros_like(qd), q_cmd, (factor,)))


@pytest.mark.parametrize('n', [6, 7, 1])
def test_pack_equals_the_numpy_expression(n):
    rng = np.random.default_rng(n)
    for _ in range(50):
        arrays = [rng.normal(size=n) for _ in range(6)]
        factor = float(rng.uniform())
        out = np.full(ARRAYS * n + 1, np.nan)
        assert pack_state(*arrays, factor, out) is out
        assert np.array_equal(out, _numpy(*arrays, factor))


def test_read_only_and_strided_inputs_are_taken():
    base = np.arange(24.0)
    held = base[:6].copy()
    held.flags.writeable = False  # the hold sample's arrays are read-only
    strided = base[::4]  # a view with a stride
    out = np.empty(ARRAYS * 6 + 1)
    pack_state(held, strided, held, strided, held, strided, 0.5, out)
    assert np.array_equal(out, _numpy(held, strided, held, strided, held, strided, 0.5))


def test_the_field_list_has_eight_arrays_in_the_message_order():
    assert ARRAYS == 8
    assert [part for part, _ in FIELDS] == ['reference', 'feedback', 'error', 'output']
