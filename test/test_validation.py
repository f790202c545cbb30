"""Tests of ur_sim_driver.motion.validation: one rule per test, plus order and mapping."""

import math

import numpy as np
import pytest

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.motion.trajectory_types import CommandPoint, TrajectoryCommand
from ur_sim_driver.motion.validation import (
    check_point_sizes,
    check_time_from_start,
    map_to_config_order,
    validate_trajectory,
)

JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
Q_MIN = np.array([-2 * math.pi] * 6)
Q_MAX = np.array([2 * math.pi] * 6)
Q_MIN[2], Q_MAX[2] = -math.pi, math.pi
NOW = 50.0


def make_point(t, q=None, v=(), a=(), effort=()):
    return CommandPoint(t, [0.1] * 6 if q is None else q, v, a, effort)


def good_points(count=4):
    return [make_point(0.5 * (k + 1), [0.1 * k] * 6, [0.0] * 6) for k in range(count)]


def validate(cmd, allow_partial=False, allow_nonzero=False, now=NOW):
    return validate_trajectory(
        cmd,
        joint_names_config=JOINTS,
        q_min=Q_MIN,
        q_max=Q_MAX,
        now=now,
        allow_partial=allow_partial,
        allow_nonzero_end_velocity=allow_nonzero,
    )


def with_points(points, names=JOINTS, stamp=0.0):
    return TrajectoryCommand(names, points, stamp)


def test_good_command_passes():
    assert validate(with_points(good_points())) is None


def test_good_command_in_any_joint_order_passes():
    names = tuple(reversed(JOINTS))
    assert validate(with_points(good_points(), names)) is None


def test_joint_count_mismatch_rejected_unless_partial_allowed():
    points = [CommandPoint(1.0, [0.2] * 5)]
    cmd = with_points(points, JOINTS[:5])
    reason = validate(cmd)
    assert reason is not None and "5" in reason and "6" in reason and "partial" in reason
    assert validate(cmd, allow_partial=True) is None


def test_empty_joint_names_rejected():
    reason = validate(with_points([CommandPoint(1.0, [])], names=()), allow_partial=True)
    assert reason == "joint_names is empty"


def test_empty_joint_names_reports_count_first_without_partial():
    # Upstream checks the joint count before emptiness.
    reason = validate(with_points([CommandPoint(1.0, [])], names=()))
    assert "has 0 joints" in reason


def test_empty_points_rejected():
    reason = validate(with_points([]))
    assert reason is not None and "points is empty" in reason


def test_unknown_joint_name_rejected():
    names = JOINTS[:3] + ("forearm_joint",) + JOINTS[4:]
    reason = validate(with_points(good_points(), names))
    assert "joint_names[3]" in reason and "'forearm_joint'" in reason


def test_duplicate_joint_name_rejected():
    names = JOINTS[:5] + ("elbow_joint",)
    reason = validate(with_points(good_points(), names))
    assert "joint_names[5]" in reason and "elbow_joint" in reason and "joint_names[2]" in reason


def test_nonzero_last_velocity_rejected_unless_allowed():
    points = good_points(3)
    points[2] = make_point(1.5, [0.2] * 6, [0, 0, 0, 0.25, 0, 0])
    cmd = with_points(points)
    reason = validate(cmd)
    assert "points[2].velocities[wrist_1_joint]" in reason and "0.25" in reason
    assert validate(cmd, allow_nonzero=True) is None


def test_last_velocity_below_float_epsilon_counts_as_zero():
    points = good_points(2)
    points[1] = make_point(1.0, [0.2] * 6, [1e-9] * 6)
    assert validate(with_points(points)) is None


def test_nonzero_velocity_at_inner_point_is_fine():
    points = good_points(3)
    points[1] = make_point(1.0, [0.2] * 6, [0.3] * 6)
    assert validate(with_points(points)) is None


def test_trajectory_ending_in_the_past_rejected():
    cmd = with_points(good_points(4), stamp=40.0)  # ends at 40 + 2.0 = 42 < 50
    reason = validate(cmd)
    assert "ends in the past" in reason and "42.000" in reason and "50.000" in reason
    assert validate(cmd, now=41.9) is None


def test_zero_stamp_never_in_the_past():
    assert validate(with_points(good_points(4)), now=1e9) is None


def test_equal_times_rejected():
    points = good_points(4)
    points[2] = make_point(1.0, [0.2] * 6, [0.0] * 6)  # same as points[1]
    reason = validate(with_points(points))
    assert "points[2].time_from_start" in reason and "points[1]" in reason


def test_decreasing_times_rejected():
    points = good_points(4)
    points[3] = make_point(0.2, [0.2] * 6, [0.0] * 6)
    reason = check_time_from_start(with_points(points), 3)
    assert reason is not None and "points[3]" in reason and "0.2" in reason


def test_first_time_zero_allowed_negative_rejected():
    points = good_points(3)
    points[0] = make_point(0.0, [0.0] * 6, [0.0] * 6)
    assert validate(with_points(points)) is None
    points[0] = make_point(-0.5, [0.0] * 6, [0.0] * 6)
    reason = validate(with_points(points))
    assert "points[0].time_from_start" in reason and "negative" in reason


@pytest.mark.parametrize("field", ["positions", "velocities", "accelerations"])
def test_size_mismatch_rejected(field):
    points = good_points(3)
    kwargs = {"q": [0.1] * 6, "v": [0.0] * 6, "a": [0.0] * 6}
    kwargs[{"positions": "q", "velocities": "v", "accelerations": "a"}[field]] = [0.0] * 5
    points[1] = make_point(1.0, **kwargs)
    reason = validate(with_points(points))
    assert f"points[1].{field} has 5 values" in reason and "6" in reason


def test_empty_positions_rejected_but_empty_velocities_allowed():
    cmd = with_points([make_point(1.0, q=[], v=[])])
    assert "points[0].positions has 0 values" in check_point_sizes(cmd, 0)
    assert validate(with_points([make_point(1.0, v=[], a=[])])) is None


def test_effort_rejected():
    points = good_points(2)
    points[1] = make_point(1.0, [0.2] * 6, [0.0] * 6, effort=[1.0] * 6)
    reason = validate(with_points(points))
    assert "points[1].effort" in reason


@pytest.mark.parametrize(
    "point, expected",
    [
        (make_point(1.0, [0.1, 0.1, 0.1, 0.1, math.nan, 0.1]), "points[1].positions[wrist_2_joint]"),
        (make_point(1.0, v=[0, math.inf, 0, 0, 0, 0]), "points[1].velocities[shoulder_lift_joint]"),
        (make_point(1.0, a=[0, 0, 0, 0, 0, -math.inf]), "points[1].accelerations[wrist_3_joint]"),
    ],
)
def test_non_finite_rejected(point, expected):
    # The bad point sits in the middle so the end-velocity rule does not see it first.
    reason = validate(with_points([make_point(0.5), point, make_point(2.0)]))
    assert reason is not None and expected in reason and "not finite" in reason


def test_non_finite_time_rejected():
    reason = validate(with_points([make_point(0.5), make_point(math.inf)]))
    assert reason is not None and "points[1].time_from_start" in reason and "not finite" in reason


def test_position_outside_limits_rejected():
    points = good_points(5)
    points[3] = make_point(2.0, [0.0, 0.0, 3.5, 0.0, 0.0, 0.0], [0.0] * 6)
    reason = validate(with_points(points))
    assert reason == ("points[3].positions[elbow_joint] = 3.5 rad is outside the joint limits [-3.1416, 3.1416]")


def test_position_at_limit_accepted():
    points = [make_point(1.0, [2 * math.pi, -2 * math.pi, math.pi, 0, 0, 0])]
    assert validate(with_points(points)) is None


def test_upstream_order_unknown_name_before_end_velocity():
    names = ("foo",) + JOINTS[1:]
    points = [make_point(1.0, v=[1.0] * 6)]
    assert "'foo'" in validate(with_points(points, names))


def test_point_checks_interleave_per_point():
    # Upstream checks time, sizes and effort of point i before looking at point i+1.
    late_time = good_points(4)
    late_time[1] = make_point(1.0, [0.0] * 5)
    late_time[3] = make_point(0.1)
    assert "points[1].positions" in validate(with_points(late_time))
    early_time = good_points(4)
    early_time[1] = make_point(0.2)
    early_time[3] = make_point(2.0, [0.0] * 5)
    assert "points[1].time_from_start" in validate(with_points(early_time))


def test_upstream_rules_before_ours():
    points = good_points(3)
    points[0] = make_point(0.5, [9.0] * 6)  # outside limits
    points[2] = make_point(1.5, [0.0] * 6, effort=[1.0] * 6)
    assert "effort" in validate(with_points(points))


def test_map_reorders_by_name():
    names = (
        "wrist_3_joint",
        "shoulder_pan_joint",
        "elbow_joint",
        "wrist_1_joint",
        "shoulder_lift_joint",
        "wrist_2_joint",
    )
    q = [6.0, 1.0, 3.0, 4.0, 2.0, 5.0]
    v = [0.6, 0.1, 0.3, 0.4, 0.2, 0.5]
    cmd = TrajectoryCommand(names, [CommandPoint(1.0, q, v), CommandPoint(2.0, q)])
    pts = map_to_config_order(cmd, JOINTS, np.zeros(6))
    assert pts.joint_names == JOINTS
    np.testing.assert_allclose(pts.positions[0], [1, 2, 3, 4, 5, 6])
    np.testing.assert_allclose(pts.velocities[0], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    assert pts.has_velocities.tolist() == [True, False]
    assert pts.has_accelerations.tolist() == [False, False]
    np.testing.assert_allclose(pts.times, [1.0, 2.0])


def test_map_partial_goal_holds_missing_joints():
    current = np.array([0.5, -1.0, 1.2, -0.3, 0.7, 0.9])
    cmd = TrajectoryCommand(
        ("elbow_joint", "shoulder_pan_joint"),
        [CommandPoint(1.0, [2.0, 1.0], [0.3, 0.1], [0.2, 0.4]), CommandPoint(2.0, [2.5, 1.5])],
        header_stamp=3.0,
    )
    pts = map_to_config_order(cmd, JOINTS, current)
    expected = current.copy()
    expected[2], expected[0] = 2.0, 1.0
    np.testing.assert_allclose(pts.positions[0], expected)
    for j in (1, 3, 4, 5):
        np.testing.assert_allclose(pts.positions[:, j], current[j])
        np.testing.assert_allclose(pts.velocities[:, j], 0.0)
        np.testing.assert_allclose(pts.accelerations[:, j], 0.0)
    assert pts.velocities[0, 2] == 0.3 and pts.accelerations[0, 0] == 0.4
    assert pts.header_stamp == 3.0


def test_map_refuses_unvalidated_command():
    cmd = TrajectoryCommand(("nope",), [CommandPoint(1.0, [0.0])])
    with pytest.raises(TrajectoryError, match="nope"):
        map_to_config_order(cmd, JOINTS, np.zeros(6))


def test_mapped_arrays_are_read_only():
    pts = map_to_config_order(with_points(good_points()), JOINTS, np.zeros(6))
    with pytest.raises(ValueError):
        pts.positions[0, 0] = 1.0


V_MAX = np.array([2.0, 2.0, 3.0, 3.0, 3.0, 3.0])


def validate_with_speed(cmd):
    return validate_trajectory(cmd, joint_names_config=JOINTS, q_min=Q_MIN, q_max=Q_MAX, now=NOW, v_max=V_MAX)


def test_velocity_limits_pass_for_slow_trajectories():
    assert validate_with_speed(with_points(good_points())) is None


def test_given_velocity_above_limit_names_point_joint_and_limit():
    points = good_points()
    points[1] = make_point(1.0, [0.1] * 6, [0.0, 2.5, 0.0, 0.0, 0.0, 0.0])
    reason = validate_with_speed(with_points(points))
    assert reason == ("points[1].velocities[shoulder_lift_joint] = 2.5 rad/s exceeds the velocity limit "
                      "2.0000 rad/s")


def test_segment_mean_velocity_above_limit_is_rejected():
    # elbow moves 1.6 rad in 0.5 s = 3.2 rad/s > 3.0 rad/s
    points = [make_point(0.5, [0.0] * 6), make_point(1.0, [0.0, 0.0, 1.6, 0.0, 0.0, 0.0])]
    reason = validate_with_speed(with_points(points))
    assert reason is not None
    assert 'points[0] -> points[1] moves elbow_joint at 3.2 rad/s' in reason and '3.0000 rad/s' in reason


def test_first_point_jump_is_not_a_velocity_violation():
    # The segment from the measured state is the path tolerance's business (upstream jump semantics).
    assert validate_with_speed(with_points([make_point(0.0, [1.5] * 6), make_point(1.0, [1.5] * 6)])) is None
