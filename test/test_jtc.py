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


def _run(velocity_errors: bool, qd_offset: float):
    """A 0.4 rad move in 0.4 s on joint a, tracked in position exactly but reporting `qd_offset` [rad/s] more
    velocity than asked for: (outcome code, reason) of the goal."""
    from ur_sim_driver.motion.trajectory_types import TrajectoryPoints
    tol = default_tolerances(NAMES, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=0.5)
    jtc = TrajectoryController(NAMES, tol, np.zeros(2), *LIMITS, velocity_errors=velocity_errors)
    dt, q = 0.002, np.zeros(2)
    jtc.update(0.0, dt, q, q)
    points = TrajectoryPoints(NAMES, np.array([0.4]), np.array([[0.4, 0.0]]), np.zeros((1, 2)), np.zeros((1, 2)),
                              np.array([False]), np.array([False]))
    jtc.start(points, dt, q, q, token='goal')
    qd = np.zeros(2)
    for k in range(1, 1000):
        sample, outcome = jtc.update(k * dt, dt, q, qd)
        q = np.array(sample.positions)  # exact in position,
        qd = np.array(sample.velocities) + qd_offset  # off in velocity
        if outcome is not None:
            return outcome.code, f'{outcome.message} ({outcome.detail})'
    raise AssertionError('the goal did not end')


def test_velocity_errors_are_not_checked_when_the_controller_commands_position_only():
    """As upstream's JTC in the driver's configuration (position command interface): a reported velocity 0.5 rad/s
    off the reference, beyond the 0.2 rad/s stopped_velocity_tolerance, neither aborts nor fails the goal; with a
    velocity command interface it fails the goal tolerance."""
    code, reason = _run(velocity_errors=False, qd_offset=0.5)
    assert code == 0, reason
    code, reason = _run(velocity_errors=True, qd_offset=0.5)
    assert code != 0 and 'velocity error' in reason


def _started(token, goal_time=0.0):
    from ur_sim_driver.motion.trajectory_types import TrajectoryPoints
    tol = default_tolerances(NAMES, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=goal_time)
    # Unscaled (the plain JTC): trajectory time runs on however the arm lags.
    jtc = TrajectoryController(NAMES, tol, np.zeros(2), *LIMITS, scaled=False)
    jtc.update(0.0, 0.002, np.zeros(2), np.zeros(2))
    points = TrajectoryPoints(NAMES, np.array([0.4]), np.array([[0.4, 0.0]]), np.zeros((1, 2)), np.zeros((1, 2)),
                              np.array([False]), np.array([False]))
    jtc.start(points, 0.002, np.zeros(2), np.zeros(2), token=token)
    return jtc


def _drive(jtc, arm, cycles=1000):
    """Run until an outcome, the arm at `arm(sample)` each cycle: (outcome, cycles run)."""
    q = np.zeros(2)
    for k in range(2, cycles):
        sample, outcome = jtc.update(k * 0.002, 0.002, q, np.zeros(2))
        q = arm(sample)
        if outcome is not None:
            return outcome, k
    return None, cycles


@pytest.mark.parametrize('token', ['goal', None])
def test_a_path_violation_holds_the_arm_for_a_goal_and_a_topic_trajectory_alike(token):
    """Upstream checks the path tolerance of topic trajectories too (with the default tolerances) and holds the
    measured position; only a goal has a result to send."""
    jtc = _started(token)
    stuck = np.zeros(2)  # the arm does not follow: 0.2 rad of error after ~0.2 s
    outcome, k = _drive(jtc, lambda sample: stuck)
    assert outcome is not None and outcome.token == token and outcome.code == -4  # PATH_TOLERANCE_VIOLATED
    assert outcome.message == ('Aborted due to path tolerance violation' if token else
                               'Holding position due to state tolerance violation')
    assert 'a position error' in outcome.detail and 'exceeds the tolerance 0.2 rad' in outcome.detail
    assert jtc.trajectory is None
    held, _ = jtc.update((k + 1) * 0.002, 0.002, stuck, np.zeros(2))
    assert np.array_equal(held.positions, stuck) and np.array_equal(jtc.stop, stuck)  # holding where the arm is


def test_success_and_a_missed_goal_time_in_upstreams_words():
    outcome, _ = _drive(_started('goal'), lambda sample: np.array(sample.positions))
    assert (outcome.code, outcome.message, outcome.detail) == (0, 'Goal successfully reached!', '')
    # Ends 0.15 rad short of the goal (within the path tolerance, outside the 0.1 rad goal tolerance).
    short = _started('goal', goal_time=0.1)
    outcome, _ = _drive(short, lambda sample: np.minimum(sample.positions, [0.25, 0.0]))
    assert outcome.code == -5 and outcome.message.startswith('Aborted due to goal_time_tolerance exceeding by 0.1')
    assert outcome.message.endswith(' seconds') and 'goal tolerance violated' in outcome.detail
    topic = _started(None, goal_time=0.1)
    outcome, _ = _drive(topic, lambda sample: np.minimum(sample.positions, [0.25, 0.0]))
    assert (outcome.token, outcome.message) == (None, 'Exceeded goal_time_tolerance: holding position...')
