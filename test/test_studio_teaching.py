"""The studio's teaching state: waypoints, selection, seed 1's keys, saved and skipped waypoints."""
import math

import numpy as np
import pytest

from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.studio.teaching import TeachState


def _three() -> TeachState:
    return TeachState.from_arrays(np.eye(3), np.zeros(3))


def test_defaults_are_seed_1s_saved_waypoints():
    s = TeachState.defaults()
    assert len(s.waypoints) == 22 and s.selected == 0
    assert np.array_equal(s.planned_arrays()[0], DEFAULT_WAYPOINTS)
    assert all(w.saved and w.orientation_zyx == DEFAULT_ORIENTATION_ZYX for w in s.waypoints)
    edited = s.delete(3).add([0.0, 0.5, 0.2]).with_step(2.0)
    back = edited.restore_defaults()
    assert back.waypoints == s.waypoints and back.step_deg == 2.0


def test_add_goes_after_the_selected_one_unsaved_with_its_orientation():
    s = _three().select(0).set_orientation(0, (0.1, 0.2, 0.3)).key('c')
    s = s.add([5.0, 5.0, 5.0])
    assert s.selected == 1 and s.waypoints[1].position == (5.0, 5.0, 5.0)
    assert s.waypoints[1].orientation_zyx == (0.1, 0.2, 0.3) and not s.waypoints[1].saved
    assert [w.position[0] for w in s.waypoints] == [1.0, 5.0, 0.0, 0.0]
    empty = TeachState().add([1.0, 2.0, 3.0])
    assert empty.selected == 0 and empty.waypoints[0].orientation_zyx == DEFAULT_ORIENTATION_ZYX


def test_move_delete_reorder():
    s = _three().move(2, [0.0, 0.0, 9.0])
    assert s.waypoints[2].position == (0.0, 0.0, 9.0) and s.waypoints[2].saved
    s = s.reorder(2, 0)
    assert [w.position for w in s.waypoints] == [(0.0, 0.0, 9.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
    assert s.selected == 0
    s = s.select(1).delete(1)
    assert len(s.waypoints) == 2 and s.selected == 0
    assert s.delete(0).delete(0).selected is None
    with pytest.raises(ValueError, match=r'waypoint index 7 is not in \[0, 1\]'):
        s.select(7)
    with pytest.raises(ValueError, match='position'):
        s.move(0, [1.0, float('nan'), 0.0])


@pytest.mark.parametrize('key, component, sign', [('up', 2, 1), ('down', 2, -1), ('right', 1, 1), ('left', 1, -1)])
def test_keys_turn_the_selected_orientation_by_the_step(key, component, sign):
    s = TeachState.defaults().with_step(7.5).select(4)
    after = s.key(key)
    delta = np.subtract(after.waypoints[4].orientation_zyx, s.waypoints[4].orientation_zyx)
    expected = np.zeros(3)
    expected[component] = sign * math.radians(7.5)
    assert np.allclose(delta, expected, atol=1e-15)
    assert not after.waypoints[4].saved and after.waypoints[3] == s.waypoints[3]


def test_c_saves_n_moves_on_and_unsaved_waypoints_are_skipped():
    s = TeachState.defaults().select(21)
    s = s.key('up')  # edited, not saved
    assert s.skipped_indices() == (21,) and len(s.planned_indices()) == 21
    s = s.key('n')
    assert s.selected == 0  # wraps
    s = s.select(21).key('c')
    assert s.skipped_indices() == () and s.waypoints[21].saved
    # a clicked waypoint is unsaved until C
    s = s.add([0.0, 0.6, 0.2])
    assert s.skipped_indices() == (22,)
    # with nothing saved, every waypoint is planned (the seed's default orientations)
    fresh = TeachState.from_arrays(np.eye(3), np.zeros(3), saved=False)
    assert fresh.planned_indices() == (0, 1, 2)


def test_bad_step_and_key_are_named():
    with pytest.raises(ValueError, match=r'step: 0 deg is not in \(0, 45\]'):
        TeachState().with_step(0)
    with pytest.raises(ValueError, match="key 'x' is not one of"):
        TeachState.defaults().key('x')
    assert TeachState().key('up') == TeachState()  # nothing selected: nothing to turn


def test_gizmo_rotation_sets_the_orientation():
    from ur_glue_planner.orientation import rotation_from_zyx_euler
    s = TeachState.defaults().set_rotation(2, rotation_from_zyx_euler(0.2, -0.1, 0.4))
    assert s.waypoints[2].orientation_zyx == pytest.approx((0.2, -0.1, 0.4), abs=1e-12)
    assert not s.waypoints[2].saved
