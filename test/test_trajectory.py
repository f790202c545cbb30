"""Tests of ur_sim_driver.motion.trajectory against independently solved polynomials."""

import numpy as np
import pytest

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.motion.trajectory import Trajectory, interpolate
from ur_sim_driver.motion.trajectory_types import CommandPoint, TrajectoryCommand, TrajectoryPoints
from ur_sim_driver.motion.validation import map_to_config_order

JOINTS = ("a", "b", "c")
RNG = np.random.default_rng(7)


def reference_poly(boundary_start, boundary_end, duration):
    """Coefficients (lowest power first) of the polynomial meeting the boundary values.

    boundary_*: [p], [p, v] or [p, v, a] at s=0 and s=duration; solved as a linear system.
    """
    m = len(boundary_start)
    degree = 2 * m - 1
    rows, rhs = [], []
    for s, values in ((0.0, boundary_start), (duration, boundary_end)):
        for derivative, value in enumerate(values):
            row = np.zeros(degree + 1)
            for power in range(derivative, degree + 1):
                factor = np.prod(np.arange(power - derivative + 1, power + 1))
                row[power] = factor * s ** (power - derivative)
            rows.append(row)
            rhs.append(value)
    return np.linalg.solve(np.array(rows), np.array(rhs))


def eval_poly(c, s):
    p = np.polynomial.polynomial
    return p.polyval(s, c), p.polyval(s, p.polyder(c)), p.polyval(s, p.polyder(c, 2))


def points(times, q, v=None, a=None, stamp=0.0):
    q = np.asarray(q, dtype=float)
    count, n = q.shape
    return TrajectoryPoints(
        joint_names=JOINTS[:n],
        times=np.asarray(times, dtype=float),
        positions=q,
        velocities=np.zeros_like(q) if v is None else np.asarray(v, dtype=float),
        accelerations=np.zeros_like(q) if a is None else np.asarray(a, dtype=float),
        has_velocities=np.full(count, v is not None),
        has_accelerations=np.full(count, a is not None),
        header_stamp=stamp,
    )


@pytest.mark.parametrize("order", [1, 2, 3])
def test_interpolate_matches_solved_polynomial(order):
    T = 1.7
    p0, p1 = RNG.normal(size=3), RNG.normal(size=3)
    v0, v1 = RNG.normal(size=3), RNG.normal(size=3)
    a0, a1 = RNG.normal(size=3), RNG.normal(size=3)
    args = (
        p0,
        v0 if order > 1 else None,
        a0 if order > 2 else None,
        p1,
        v1 if order > 1 else None,
        a1 if order > 2 else None,
        T,
    )
    for s in (0.0, 0.3, 1.1, T):
        q, qd, qdd = interpolate(*args, s)
        for j in range(3):
            start = [p0[j], v0[j], a0[j]][:order]
            end = [p1[j], v1[j], a1[j]][:order]
            rq, rqd, rqdd = eval_poly(reference_poly(start, end, T), s)
            assert q[j] == pytest.approx(rq, abs=1e-10)
            assert qd[j] == pytest.approx(rqd, abs=1e-10)
            assert qdd[j] == pytest.approx(rqdd, abs=1e-9)


def test_linear_between_positions_only_points():
    traj = Trajectory(points([1.0, 3.0], [[0.0, 1.0, 2.0], [2.0, 1.0, -2.0]]), 10.0, np.zeros(3))
    sample = traj.sample(12.0)  # halfway between the points
    np.testing.assert_allclose(sample.positions, [1.0, 1.0, 0.0])
    np.testing.assert_allclose(sample.velocities, [1.0, 0.0, -2.0])
    np.testing.assert_allclose(sample.accelerations, 0.0)
    assert sample.segment_index == 1 and not sample.ended


def test_cubic_matches_knots_and_is_continuous():
    q = RNG.normal(size=(4, 3))
    v = RNG.normal(size=(4, 3))
    v[-1] = 0.0
    times = [0.5, 1.0, 2.2, 3.0]
    traj = Trajectory(points(times, q, v), 0.0, q[0], v[0])
    eps = 1e-7
    for k in range(1, 3):
        before, after = traj.sample(times[k] - eps), traj.sample(times[k] + eps)
        np.testing.assert_allclose(before.positions, q[k], atol=1e-6)
        np.testing.assert_allclose(after.positions, q[k], atol=1e-6)
        np.testing.assert_allclose(before.velocities, v[k], atol=1e-5)
        np.testing.assert_allclose(after.velocities, v[k], atol=1e-5)
        assert (before.segment_index, after.segment_index) == (k, k + 1)


def test_quintic_matches_accelerations_at_knots():
    q = RNG.normal(size=(3, 3))
    v = RNG.normal(size=(3, 3))
    a = RNG.normal(size=(3, 3))
    times = [1.0, 2.0, 2.5]
    traj = Trajectory(points(times, q, v, a), 5.0, q[0])
    knot = traj.sample(6.0)  # exactly at point 0 -> start of segment 0-1
    np.testing.assert_allclose(knot.positions, q[0], atol=1e-12)
    np.testing.assert_allclose(knot.velocities, v[0], atol=1e-12)
    np.testing.assert_allclose(knot.accelerations, a[0], atol=1e-12)
    end = traj.sample(7.0 - 1e-8)
    np.testing.assert_allclose(end.accelerations, a[1], atol=1e-5)
    s = 0.37
    ref = reference_poly([q[1, 2], v[1, 2], a[1, 2]], [q[2, 2], v[2, 2], a[2, 2]], 0.5)
    assert traj.sample(7.0 + s).positions[2] == pytest.approx(eval_poly(ref, s)[0], abs=1e-10)


def test_first_segment_starts_from_measured_state_cubic():
    q0, qd0 = np.array([0.3, -0.2, 0.1]), np.array([0.5, 0.0, -0.4])
    pts = points([2.0, 3.0], [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]], np.zeros((2, 3)))
    traj = Trajectory(pts, 10.0, q0, qd0)
    start = traj.sample(10.0)
    np.testing.assert_allclose(start.positions, q0)
    np.testing.assert_allclose(start.velocities, qd0)
    assert start.segment_index == 0 and not start.ended
    ref = reference_poly([q0[0], qd0[0]], [1.0, 0.0], 2.0)
    assert traj.sample(10.8).positions[0] == pytest.approx(eval_poly(ref, 0.8)[0], abs=1e-12)


def test_first_segment_quintic_with_zero_start_acceleration():
    # Point 0 has accelerations, the measured state has none: zero-filled (issue #2015).
    q0, qd0 = np.zeros(3), np.array([0.2, 0.0, 0.0])
    pts = points([1.0], [[1.0, 0.0, 0.0]], np.zeros((1, 3)), np.zeros((1, 3)))
    traj = Trajectory(pts, 0.0, q0, qd0)
    np.testing.assert_allclose(traj.sample(0.0).accelerations, 0.0, atol=1e-12)
    ref = reference_poly([0.0, 0.2, 0.0], [1.0, 0.0, 0.0], 1.0)
    assert traj.sample(0.4).positions[0] == pytest.approx(eval_poly(ref, 0.4)[0], abs=1e-12)


def test_first_segment_linear_ignores_measured_velocity():
    traj = Trajectory(points([2.0], [[2.0, 0.0, 0.0]]), 0.0, np.zeros(3), np.array([5.0, 0, 0]))
    sample = traj.sample(0.5)
    np.testing.assert_allclose(sample.positions, [0.5, 0.0, 0.0])
    np.testing.assert_allclose(sample.velocities, [1.0, 0.0, 0.0])


def test_first_point_at_time_zero_jumps_to_it():
    q = [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]
    traj = Trajectory(points([0.0, 1.0], q), 4.0, np.zeros(3))
    sample = traj.sample(4.0)
    np.testing.assert_allclose(sample.positions, q[0])
    assert sample.segment_index == 1


def test_hold_after_end():
    q = [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]
    # Non-zero end derivatives (allow_nonzero_velocity_at_trajectory_end): still held at rest.
    v = [[0.0, 0.0, 0.0], [0.3, 0.0, -0.3]]
    a = [[0.0, 0.0, 0.0], [0.5, 0.5, 0.5]]
    traj = Trajectory(points([1.0, 2.0], q, v, a), 1.0, np.zeros(3))
    assert traj.end_time == 3.0
    assert not traj.sample(3.0 - 1e-9).ended
    for t in (3.0, 3.5, 100.0):
        sample = traj.sample(t)
        assert sample.ended and sample.segment_index == 1
        np.testing.assert_allclose(sample.positions, q[1])
        np.testing.assert_allclose(sample.velocities, 0.0)
        np.testing.assert_allclose(sample.accelerations, 0.0)


def test_start_uses_header_stamp_and_state_time():
    pts = points([1.0], [[1.0, 0.0, 0.0]], stamp=20.0)
    traj = Trajectory.start(pts, now=18.0, positions=np.zeros(3))
    assert traj.start_time == 20.0 and traj.state_time == 18.0 and traj.end_time == 21.0
    np.testing.assert_allclose(traj.sample(19.5).positions, [0.5, 0.0, 0.0])  # 18 -> 21
    before = traj.sample(17.0)
    np.testing.assert_allclose(before.positions, 0.0)
    assert not before.ended


def test_start_now_when_stamp_is_zero():
    traj = Trajectory.start(points([2.0], [[1.0, 0.0, 0.0]]), now=7.0, positions=np.zeros(3))
    assert traj.start_time == 7.0 and traj.end_time == 9.0


def test_mixed_velocities_per_segment():
    # Point 1 has no velocities: segments touching it are linear, upstream per segment.
    pts = TrajectoryPoints(
        joint_names=("a",),
        times=np.array([1.0, 2.0, 3.0]),
        positions=np.array([[0.0], [1.0], [3.0]]),
        velocities=np.array([[0.0], [0.0], [0.0]]),
        accelerations=np.zeros((3, 1)),
        has_velocities=np.array([True, False, True]),
        has_accelerations=np.zeros(3, dtype=bool),
    )
    traj = Trajectory(pts, 0.0, np.zeros(1))
    assert traj.sample(1.25).positions[0] == pytest.approx(0.25)
    assert traj.sample(2.5).velocities[0] == pytest.approx(2.0)


def test_accelerations_without_velocities_fall_back_to_linear():
    pts = points([1.0, 2.0], [[0.0] * 3, [1.0] * 3], a=np.ones((2, 3)))
    pts = TrajectoryPoints(**{**pts.__dict__, "has_velocities": np.array([False, False])})
    traj = Trajectory(pts, 0.0, np.zeros(3))
    np.testing.assert_allclose(traj.sample(1.5).positions, 0.5)


def test_partial_goal_keeps_other_joints_still():
    current = np.array([0.4, -0.6, 0.8])
    cmd = TrajectoryCommand(("b",), [CommandPoint(1.0, [1.0]), CommandPoint(2.0, [0.0])])
    traj = Trajectory(map_to_config_order(cmd, JOINTS, current), 0.0, current)
    for t in (0.3, 1.0, 1.7, 5.0):
        sample = traj.sample(t)
        assert sample.positions[0] == pytest.approx(0.4)
        assert sample.positions[2] == pytest.approx(0.8)
    assert traj.sample(0.5).positions[1] == pytest.approx(-0.6 + 0.5 * 1.6)


def test_bad_start_state_shape_rejected():
    with pytest.raises(TrajectoryError, match="start_positions"):
        Trajectory(points([1.0], [[0.0] * 3]), 0.0, np.zeros(2))
