"""The trajectory controller's core (jtc.py) without ROS: what it commands while holding."""
import numpy as np
import pytest

from ur_sim_driver.motion.jtc import TrajectoryController
from ur_sim_driver.motion.tolerances import default_tolerances

NAMES = ('a', 'b')
LIMITS = np.array([3.0, 2.0]), np.array([5.0, 5.0])


def _holding(q0) -> TrajectoryController:
    tol = default_tolerances(NAMES, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=0.0)
    return TrajectoryController(NAMES, tol, np.asarray(q0, dtype=float), *LIMITS)


def test_holding_commands_the_held_position_at_rest_with_read_only_arrays():
    jtc = _holding([0.3, -0.4])
    q = np.zeros(2)
    first, outcome = jtc.update(0.0, 0.002, q, q)
    assert outcome is None and first.ended
    assert np.array_equal(first.positions, [0.3, -0.4]) and not first.velocities.any() and not first.accelerations.any()
    # The sample is shared by every holding cycle: a consumer that wrote into it would corrupt the next cycles.
    for array in (first.positions, first.velocities, first.accelerations):
        with pytest.raises(ValueError, match='read-only'):
            array[0] = 1.0
    again, _ = jtc.update(0.002, 0.002, q, q)
    assert again is first


def test_a_new_hold_gives_a_new_sample():
    jtc = _holding([0.3, -0.4])
    q = np.zeros(2)
    before, _ = jtc.update(0.0, 0.002, q, q)
    held = np.array([0.1, 0.2])
    jtc.hold(held)
    held[0] = 9.0  # the caller's array is copied, not kept
    after, _ = jtc.update(0.002, 0.002, q, q)
    assert np.array_equal(after.positions, [0.1, 0.2]) and np.array_equal(before.positions, [0.3, -0.4])
    assert np.array_equal(jtc.stop, [0.1, 0.2])
