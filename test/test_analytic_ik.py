"""Closed-form UR IK: round trips on every UR type and all eight branches, and the URDF's own FK."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.orientation import rot_x, rot_z
from ur_sim_driver.description.analytic_ik import (
    N_BRANCHES,
    UrAnalyticIK,
    angular_distance,
    follow_branch,
    nearest_branch,
    wrap_angle,
)
from ur_sim_driver.description.params import DH, UR_TYPES, joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

TIP = get_tool("dispenser").tip_in_tool0()


def random_q(rng: np.random.Generator, n: int) -> np.ndarray:
    """Configurations away from the three singularities (wrist, elbow, shoulder) by construction."""
    q = rng.uniform(-math.pi, math.pi, (n, 6))
    keep = (np.abs(np.sin(q[:, 4])) > 0.05) & (np.abs(np.sin(q[:, 2])) > 0.05)
    return q[keep]


def base_pose() -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot_z(0.7) @ rot_x(0.2), (0.3, -0.1, 0.5)
    return pose


@pytest.mark.parametrize("ur_type", UR_TYPES)
@pytest.mark.parametrize("tool", [None, TIP])
def test_every_branch_reaches_the_pose_to_1e_9(ur_type, tool):
    ik = UrAnalyticIK(load_ur_params(ur_type).dh, tool, base_pose())
    q = random_q(np.random.default_rng(11), 300)
    poses = ik.fk(q)
    sols = ik.solve(poses)
    assert sols.shape == (len(q), N_BRANCHES, 6)
    valid = ~np.isnan(sols).any(axis=2)
    # every branch is exercised: each one reaches most of these poses
    assert np.all(valid.mean(axis=0) > 0.5)
    reached = ik.fk(np.where(valid[..., None], sols, 0.0))
    err = np.abs(reached - poses[:, None])[valid]
    assert err.max() < 1e-9
    assert np.all(sols[valid] >= -math.pi) and np.all(sols[valid] < math.pi)
    # the configuration the pose came from is one of them
    found = np.min(np.where(valid, angular_distance(sols, q[:, None]), np.inf), axis=1)
    assert found.max() < 1e-9


@pytest.mark.parametrize("ur_type", UR_TYPES)
def test_forward_kinematics_equals_pinocchio_on_the_project_urdf(ur_type):
    params = load_ur_params(ur_type)
    tool = get_tool("dispenser")
    pin_kin = Kinematics(build_urdf(params, tool=tool), joint_names(), tool.tip_name, base_pose=base_pose())
    ik = UrAnalyticIK(params.dh, TIP, base_pose())
    q = np.random.default_rng(5).uniform(-2 * math.pi, 2 * math.pi, (100, 6))
    np.testing.assert_allclose(ik.fk(q), np.array([pin_kin.fk(x) for x in q]), atol=1e-12)
    # and Pinocchio puts every closed-form solution on the pose
    target = pin_kin.fk(q[0])
    for sol in ik.solve(target):
        if not np.isnan(sol).any():
            np.testing.assert_allclose(pin_kin.fk(sol), target, atol=1e-9)


def test_branch_bits_are_the_signs_of_the_roots():
    ik = UrAnalyticIK(load_ur_params("ur5e").dh)
    sols = ik.solve(ik.fk(random_q(np.random.default_rng(2), 200)))
    for b in range(N_BRANCHES):
        s = sols[:, b][~np.isnan(sols[:, b]).any(axis=1)]
        assert np.all(s[:, 4] >= 0.0) if not b & 2 else np.all(s[:, 4] <= 0.0)
        assert np.all(s[:, 2] >= 0.0) if not b & 1 else np.all(s[:, 2] <= 0.0)


def test_one_branch_alone_equals_its_column_of_all_eight():
    ik = UrAnalyticIK(load_ur_params("ur10").dh, TIP)
    poses = ik.fk(random_q(np.random.default_rng(3), 50))
    every = ik.solve(poses)
    for b in range(N_BRANCHES):
        np.testing.assert_array_equal(ik.solve(poses, branch=b), every[:, b])
    assert ik.solve(poses[0], branch=5).shape == (6,)
    with pytest.raises(ValueError, match="branch 8"):
        ik.solve(poses, branch=8)


def test_poses_out_of_reach_have_no_solution():
    ik = UrAnalyticIK(load_ur_params("ur5").dh)
    far = np.eye(4)
    far[:3, 3] = (1.5, 0.0, 0.3)  # a UR5 reaches 0.85 m
    assert np.isnan(ik.solve(far)).all()
    near_axis = np.eye(4)  # the wrist centre on the base axis: closer than d4, no shoulder solution
    near_axis[:3, 3] = (0.0, 0.0, 0.4)
    assert np.isnan(ik.solve(near_axis)).all()


def test_a_non_ur_dh_table_is_refused():
    with pytest.raises(ValueError, match="not those of a UR arm"):
        UrAnalyticIK(DH(d1=0.1, a2=0.0, a3=-0.4, d4=0.1, d5=0.1, d6=0.1))
    with pytest.raises(ValueError, match="tool must be a 4x4 rigid transform"):
        UrAnalyticIK(load_ur_params("ur5").dh, np.ones((4, 4)))


def test_following_a_branch_is_continuous_across_the_pi_wrap():
    ik = UrAnalyticIK(load_ur_params("ur5e").dh)
    q = np.array([3.0, -1.2, 1.5, -1.9, 1.2, 3.0])
    path = q + np.linspace(0.0, 0.6, 61)[:, None] * np.array([1.0, 0.2, -0.3, 0.1, 0.3, 1.0])  # q1, q6 cross pi
    sols = ik.solve(ik.fk(path))
    b, dist = nearest_branch(sols[0], path[0])
    assert dist < 1e-9
    followed = follow_branch(sols[:, b], path[0])
    np.testing.assert_allclose(followed, path, atol=1e-9)  # unwrapped, not jumping by 2 pi
    shifted = follow_branch(sols[:, b], path[0] + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2 * math.pi]))
    np.testing.assert_allclose(shifted[:, 5], path[:, 5] + 2 * math.pi, atol=1e-9)  # the whole turn kept


def test_following_stops_where_the_branch_ends():
    sols = np.zeros((5, 6))
    sols[3] = np.nan
    out = follow_branch(sols, np.zeros(6))
    assert not np.isnan(out[:3]).any() and np.isnan(out[3:]).all()
    assert nearest_branch(np.full((8, 6), np.nan), np.zeros(6)) == (-1, math.inf)


def test_wrap_angle_range():
    x = np.array([-math.pi, math.pi, 3 * math.pi + 0.1, -0.1])
    np.testing.assert_allclose(wrap_angle(x), [-math.pi, -math.pi, -math.pi + 0.1, -0.1])
