"""Jerk-limited joint move to the bead and straight moves along the tool axis."""

from __future__ import annotations

import numpy as np
import pytest

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.approach import DEFAULT_JERK_FACTOR, joint_move, offset_pose, tool_axis_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rotation_angle

DT = 0.02
A_MAX = 5.0
HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])
GOAL = np.array([-0.476, -1.594, -1.903, -0.957, 1.11, 1.034])
NOZZLE = np.array([0.0, 1.0, 0.0])  # the dispenser tip frame's y: tool0's z


@pytest.fixture(scope="module")
def kin():
    return ur_kinematics("ur5", "dispenser")


def check_limits(seg, v_max, a_max, j_max):
    assert np.all(np.abs(seg.qd) <= v_max * (1 + 1e-6))
    assert np.abs(seg.qdd).max() <= a_max * (1 + 1e-6)
    jerk = np.abs(np.diff(seg.qdd, axis=0)) / np.diff(seg.times)[:, None]
    assert jerk.max() <= j_max * (1 + 1e-6)


def test_seed_move_to_the_first_waypoint_takes_four_seconds(kin):
    seg = joint_move(HOME, GOAL, kin.v_max, A_MAX, DT, min_duration=4.0, velocity_scale=0.5)
    assert seg.duration == pytest.approx(4.0)
    np.testing.assert_allclose(seg.q[0], HOME, atol=1e-12)
    np.testing.assert_allclose(seg.q[-1], GOAL, atol=1e-12)
    np.testing.assert_allclose(seg.qd[-1], 0.0, atol=1e-12)
    np.testing.assert_allclose(seg.qdd[-1], 0.0, atol=1e-9)
    np.testing.assert_allclose(np.diff(seg.times), DT, atol=1e-9)
    check_limits(seg, 0.5 * kin.v_max, A_MAX, DEFAULT_JERK_FACTOR * A_MAX)


def test_a_move_from_a_moving_state_is_continuous_and_within_limits(kin):
    qd0 = np.array([0.3, -0.2, 0.0, 0.4, 0.0, -0.5])
    qdd0 = np.array([1.0, 0.0, -1.0, 0.0, 0.5, 0.0])
    seg = joint_move(HOME, GOAL, kin.v_max, A_MAX, DT, qd0=qd0, qdd0=qdd0)
    np.testing.assert_allclose(seg.qd[0], qd0, atol=1e-12)
    np.testing.assert_allclose(seg.qdd[0], qdd0, atol=1e-12)
    np.testing.assert_allclose(seg.q[-1], GOAL, atol=1e-12)
    assert seg.duration / DT == pytest.approx(round(seg.duration / DT), abs=1e-9)
    check_limits(seg, kin.v_max, A_MAX, DEFAULT_JERK_FACTOR * A_MAX)
    # positions and velocities agree: trapezoid rule on the samples
    step = np.diff(seg.q, axis=0) - DT * (seg.qd[1:] + seg.qd[:-1]) / 2
    assert np.abs(step).max() < 1e-3


def test_without_a_minimum_the_move_is_as_fast_as_the_limits_allow(kin):
    slow = joint_move(HOME, GOAL, kin.v_max, A_MAX, DT, velocity_scale=0.5)
    fast = joint_move(HOME, GOAL, kin.v_max, A_MAX, DT)
    assert fast.duration < slow.duration < 4.0
    # the joint with the longest way (elbow, 1.9 rad) must hit a limit at some point
    assert np.abs(fast.qdd).max() == pytest.approx(A_MAX, rel=1e-3) or np.any(
        np.abs(fast.qd) >= kin.v_max * (1 - 1e-3))


def test_a_robot_already_at_rest_on_the_goal_gets_one_sample(kin):
    seg = joint_move(GOAL, GOAL, kin.v_max, A_MAX, DT)
    assert seg.duration == 0.0 and seg.q.shape == (1, 6)
    np.testing.assert_array_equal(seg.q[0], GOAL)


def test_impossible_moves_raise():
    v = np.full(6, 1.0)
    with pytest.raises(PlanningError, match=r"approach: joint 1 would leave its limits \[-2\.0000, 2\.0000\]"):
        # from -1.57 moving at -1 rad/s, the shoulder overshoots -2 rad before it can stop
        joint_move(HOME, GOAL, v, A_MAX, DT, qd0=np.array([0.0, -1.0, 0, 0, 0, 0]), j_max=1.0,
                   q_min=np.full(6, -2.0), q_max=np.full(6, 2.0))
    with pytest.raises(ValueError, match="a_max"):
        joint_move(HOME, GOAL, v, -1.0, DT)
    with pytest.raises(ValueError, match="velocity_scale"):
        joint_move(HOME, GOAL, v, A_MAX, DT, velocity_scale=0.0)


@pytest.mark.parametrize("toward", [True, False], ids=["descent", "retreat"])
def test_tool_axis_move_is_a_straight_line_from_rest_to_rest(kin, toward):
    anchor_pose = kin.fk(GOAL)
    seg = tool_axis_move(kin, GOAL, anchor_pose, NOZZLE, 0.05, 0.05, DT, toward_anchor=toward, name="m")
    anchor = -1 if toward else 0
    far = 0 if toward else -1
    np.testing.assert_array_equal(seg.q[anchor], GOAL)
    np.testing.assert_allclose(seg.qd[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(seg.qdd[[0, -1]], 0.0, atol=1e-9)
    poses = np.array([kin.fk(q) for q in seg.q])
    # far end: 5 cm back along the nozzle, i.e. up and towards the robot for the seed orientation
    expected = anchor_pose[:3, 3] - 0.05 * anchor_pose[:3, :3] @ NOZZLE
    np.testing.assert_allclose(poses[far, :3, 3], expected, atol=1e-6)
    np.testing.assert_allclose(offset_pose(anchor_pose, NOZZLE, 0.05)[:3, 3], expected, atol=1e-15)
    # on the line, same orientation all along
    u = anchor_pose[:3, :3] @ NOZZLE
    rel = poses[:, :3, 3] - anchor_pose[:3, 3]
    assert np.abs(rel - np.outer(rel @ u, u)).max() < 1e-6
    assert max(rotation_angle(p[:3, :3], anchor_pose[:3, :3]) for p in poses) < 1e-6
    # peak speed is the requested one (quintic: at mid time)
    speed = np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1) / DT
    assert speed.max() == pytest.approx(0.05, rel=0.01)
    # and the Jacobian velocities match the motion
    jac_speed = np.array([np.linalg.norm(kin.jacobian(q)[:3] @ qd) for q, qd in zip(seg.q, seg.qd)])
    # (the duration is rounded up to whole samples: 1.875 * 0.05 / 0.05 = 1.875 s -> 1.88 s)
    assert jac_speed.max() == pytest.approx(1.875 * 0.05 / 1.88, rel=1e-3)
