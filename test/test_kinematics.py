"""Pinocchio kinematics: FK against textbook UR DH, Jacobians against finite differences, IK."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_glue_planner.motion.kinematics import Kinematics, pose_errors
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rot_x, rot_z, rotation_angle, rotation_from_zyx_euler
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.urdf import build_urdf

# DESIGN.md section 5 (UR's published DH lengths), typed here independently of config/
DH = {"ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
      "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922)}


def dh_tool0(q: np.ndarray, ur_type: str) -> np.ndarray:
    """tool0 in base_link by the classic UR DH table; base_link = DH base turned by pi about z."""
    d1, a2, a3, d4, d5, d6 = DH[ur_type]
    a, d, alpha = (0, a2, a3, 0, 0, 0), (d1, 0, 0, d4, d5, d6), (math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0)
    t = np.eye(4)
    t[:3, :3] = rot_z(math.pi)
    for i in range(6):
        ct, st, ca, sa = math.cos(q[i]), math.sin(q[i]), math.cos(alpha[i]), math.sin(alpha[i])
        t = t @ np.array([[ct, -st * ca, st * sa, a[i] * ct], [st, ct * ca, -ct * sa, a[i] * st],
                          [0, sa, ca, d[i]], [0, 0, 0, 1]])
    return t


@pytest.fixture(scope="module")
def ur5_tip() -> Kinematics:
    return ur_kinematics("ur5", "dispenser")


@pytest.fixture(scope="module")
def rng() -> np.random.Generator:
    return np.random.default_rng(7)


@pytest.mark.parametrize("ur_type", ["ur5", "ur10"])
def test_fk_of_tool0_matches_the_dh_table(ur_type, rng):
    kin = ur_kinematics(ur_type, tool=None, frame="tool0")
    for _ in range(20):
        q = rng.uniform(-math.pi, math.pi, 6)
        np.testing.assert_allclose(kin.fk(q), dh_tool0(q, ur_type), atol=1e-9)


def test_dispenser_tip_is_tool0_times_the_seed_offset(rng):
    tool0 = ur_kinematics("ur5", tool="dispenser", frame="tool0")
    tip = ur_kinematics("ur5", tool="dispenser")
    offset = np.eye(4)  # DESIGN 6: tip = tool0 * (translation (0.04, 0, 0.195), Rx(+90 deg))
    offset[:3, :3], offset[:3, 3] = rot_x(math.pi / 2), (0.04, 0.0, 0.195)
    assert tip.frame == "dispenser_tip"
    q = rng.uniform(-3, 3, 6)
    np.testing.assert_allclose(tip.fk(q), tool0.fk(q) @ offset, atol=1e-12)


def test_jacobian_matches_finite_differences_of_fk(ur5_tip, rng):
    q, h = rng.uniform(-3, 3, 6), 1e-6
    jac = ur5_tip.jacobian(q)
    t0 = ur5_tip.fk(q)
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        tp, tm = ur5_tip.fk(q + dq), ur5_tip.fk(q - dq)
        np.testing.assert_allclose((tp[:3, 3] - tm[:3, 3]) / (2 * h), jac[:3, j], atol=1e-8)
        # world-frame angular velocity: skew part of dR/dq R^T
        w = ((tp[:3, :3] - tm[:3, :3]) / (2 * h)) @ t0[:3, :3].T
        np.testing.assert_allclose([w[2, 1], w[0, 2], w[1, 0]], jac[3:, j], atol=1e-8)


def test_jacobian_dot_times_qd_is_the_time_derivative_of_j_qd(ur5_tip, rng):
    q, qd, h = rng.uniform(-3, 3, 6), rng.uniform(-1, 1, 6), 1e-5
    numeric = (ur5_tip.jacobian(q + h * qd) @ qd - ur5_tip.jacobian(q - h * qd) @ qd) / (2 * h)
    np.testing.assert_allclose(ur5_tip.jacobian_dot_times_qd(q, qd), numeric, atol=1e-7)


def test_ik_from_a_nearby_guess_converges_below_1e_6(ur5_tip, rng):
    for _ in range(10):
        q_true = rng.uniform(-2.5, 2.5, 6)
        target = ur5_tip.fk(q_true)
        res = ur5_tip.ik(target, q_true + rng.uniform(-0.2, 0.2, 6))
        assert res.converged
        assert res.residual_pos < 1e-6 and res.residual_rot < 1e-6
        reached = ur5_tip.fk(res.q)
        assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-6
        assert rotation_angle(reached[:3, :3], target[:3, :3]) < 1e-6


def test_fk_ik_round_trip_over_random_configurations(ur5_tip, rng):
    for _ in range(10):
        q = rng.uniform(-2.5, 2.5, 6)
        res = ur5_tip.ik(ur5_tip.fk(q), q + 0.05)
        assert res.converged and res.iterations <= 10  # quadratic convergence near the solution
        np.testing.assert_allclose(ur5_tip.fk(res.q), ur5_tip.fk(q), atol=1e-6)


def test_seed2_ik_reproduces_the_course_answer():
    # DESIGN 7: UR10, ee_link, target (0.6, 0, 1.0) with the base 1 m up, ZYX (pi/4, pi/4, -pi/4)
    base = np.eye(4)
    base[2, 3] = 1.0
    kin = ur_kinematics("ur10", tool=None, frame="ee_link", base_pose=base)
    target = np.eye(4)
    target[:3, :3] = rotation_from_zyx_euler(math.pi / 4, math.pi / 4, -math.pi / 4)
    target[:3, 3] = (0.6, 0.0, 1.0)
    res = kin.ik(target, np.array([0.0, 1.0, -2.0, 2.0, 1.0, 1.0]), np.ones(6))
    assert res.converged
    np.testing.assert_allclose(res.q, [-0.3824, 0.9804, -2.0033, 2.22, 0.8626, 1.3279], atol=1e-3)
    # and in base_link the seed's answer puts ee_link 1 m lower
    plain = ur_kinematics("ur10", tool=None, frame="ee_link")
    np.testing.assert_allclose(plain.fk(res.q)[:3, 3], (0.6, 0.0, 0.0), atol=1e-6)


def test_base_pose_moves_poses_and_rotates_jacobians(rng):
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rot_z(0.7) @ rot_x(0.2), (0.3, -0.1, 0.8)
    plain = ur_kinematics("ur5", tool=None, frame="tool0")
    moved = ur_kinematics("ur5", tool=None, frame="tool0", base_pose=base)
    q = rng.uniform(-3, 3, 6)
    np.testing.assert_allclose(moved.fk(q), base @ plain.fk(q), atol=1e-12)
    rb = base[:3, :3]
    np.testing.assert_allclose(moved.jacobian(q)[:3], rb @ plain.jacobian(q)[:3], atol=1e-12)
    np.testing.assert_allclose(moved.jacobian(q)[3:], rb @ plain.jacobian(q)[3:], atol=1e-12)
    np.testing.assert_allclose(moved.to_root(moved.fk(q)), plain.fk(q), atol=1e-12)
    res = moved.ik(base @ plain.fk(q), q + 0.1)
    assert res.converged


def test_zero_weights_drop_the_rotation_from_the_fit(ur5_tip, rng):
    q = rng.uniform(-2, 2, 6)
    target = ur5_tip.fk(q)
    target[:3, :3] = rot_x(0.5) @ target[:3, :3]  # a rotation we do not care about
    res = ur5_tip.ik(target, q, weights=np.array([1, 1, 1, 0, 0, 0.0]))
    assert res.converged and res.residual_pos < 1e-6
    assert res.residual_rot > 0.1


def test_ik_keeps_joints_within_limits_and_reports_failure(ur5_tip):
    far = np.eye(4)
    far[:3, 3] = (3.0, 0.0, 0.0)  # out of reach of a UR5
    res = ur5_tip.ik(far, np.array([0.0, -1.0, 3.1, 0.0, 6.0, 7.0]), max_iterations=50)
    assert not res.converged and res.residual_pos > 1.0
    assert np.all(res.q >= ur5_tip.q_min) and np.all(res.q <= ur5_tip.q_max)


def test_limits_come_from_the_model():
    params = load_ur_params("ur10")
    kin = ur_kinematics("ur10", tool=None)
    np.testing.assert_allclose(kin.v_max, np.radians([120, 120, 180, 180, 180, 180]))
    np.testing.assert_allclose(kin.q_max, params.q_max)
    assert kin.q_max[2] == pytest.approx(math.pi)  # the elbow: +-180 deg


def test_joint_and_frame_names_are_checked():
    urdf = build_urdf(load_ur_params("ur5"))
    with pytest.raises(ValueError, match="frame 'nozzle'"):
        Kinematics(urdf, joint_names(), "nozzle")
    with pytest.raises(ValueError, match="joint 'elbow'"):
        Kinematics(urdf, ["shoulder_pan_joint", "elbow"], "tool0")


def test_joint_order_is_by_name_not_by_model_order(rng):
    urdf = build_urdf(load_ur_params("ur5"))
    names = list(joint_names())
    perm = [5, 0, 3, 1, 4, 2]
    shuffled = Kinematics(urdf, [names[i] for i in perm], "tool0")
    plain = Kinematics(urdf, names, "tool0")
    q = rng.uniform(-3, 3, 6)
    np.testing.assert_allclose(shuffled.fk(q[perm]), plain.fk(q), atol=1e-12)
    np.testing.assert_allclose(shuffled.jacobian(q[perm]), plain.jacobian(q)[:, perm], atol=1e-12)
    qd = rng.uniform(-1, 1, 6)
    np.testing.assert_allclose(shuffled.jacobian_dot_times_qd(q[perm], qd[perm]),
                               plain.jacobian_dot_times_qd(q, qd), atol=1e-10)


def _variants(rng):
    """Kinematics whose batch methods must agree with the single-state ones: plain, moved base, shuffled and
    partial joint lists, and a frame before the wrist (whose wrist joints do not move it)."""
    urdf = build_urdf(load_ur_params("ur5"))
    names = list(joint_names())
    base = np.eye(4)
    base[:3, :3], base[:3, 3] = rot_z(-1.1) @ rot_x(0.4), (0.2, 0.5, -0.3)
    return [ur_kinematics("ur5", "dispenser"), ur_kinematics("ur10e", None, base_pose=base),
            Kinematics(urdf, [names[i] for i in (5, 0, 3, 1, 4, 2)], "tool0"),
            Kinematics(urdf, [names[0], names[2], names[3]], "wrist_3_link"),
            Kinematics(urdf, names, "forearm_link")]


def test_batch_fk_jacobian_and_drift_equal_the_single_state_methods(rng):
    for kin in _variants(rng):
        q, qd = rng.uniform(-3, 3, (20, kin.n)), rng.uniform(-1, 1, (20, kin.n))
        pos, rot, jac = kin.fk_jacobian_batch(q)
        drift = kin.jacobian_dot_times_qd_batch(q, qd)
        np.testing.assert_allclose(kin.jacobian_dot_times_qd_batch(q, qd, jac), drift, atol=1e-15)
        for k in range(len(q)):
            p1, r1, j1 = kin.fk_jacobian(q[k])
            np.testing.assert_allclose(pos[k], p1, atol=1e-14)
            np.testing.assert_allclose(rot[k], r1, atol=1e-14)
            np.testing.assert_allclose(jac[k], j1, atol=1e-14)
            np.testing.assert_allclose(drift[k], kin.jacobian_dot_times_qd(q[k], qd[k]), atol=1e-12)


def test_pose_errors_resolve_tiny_rotations():
    target = np.eye(4)[None].repeat(3, axis=0)
    angles = np.array([1e-13, 1e-7, 3.0])
    rotation = np.stack([rot_z(a) for a in angles])
    pos = np.array([[0.0, 0.0, 0.0], [3e-9, 4e-9, 0.0], [0.0, 0.0, 1.0]])
    err_p, err_r = pose_errors(target, pos, rotation)
    np.testing.assert_allclose(err_p, [0.0, 5e-9, 1.0], rtol=1e-12)
    np.testing.assert_allclose(err_r, angles, rtol=1e-9)


def test_path_ik_follows_nearby_poses_and_stops_at_the_first_unreachable_one(rng):
    urdf = build_urdf(load_ur_params("ur5"))
    kin = Kinematics(urdf, joint_names(), "tool0")
    q0 = np.array([0.3, -1.4, 1.6, -1.8, -1.5, 0.4])
    line = q0 + np.linspace(0.0, 0.3, 30)[:, None] * np.array([1.0, 0.5, -0.5, 0.2, 0.3, -1.0])
    targets = np.array([kin.fk(q) for q in line])
    res = kin.ik_path(targets, q0 + 0.01)
    assert res.failed is None and res.position is None
    np.testing.assert_allclose(res.q, line, atol=1e-5)
    assert res.residual_pos.max() < 1e-6 and res.residual_rot.max() < 1e-6
    targets[12, :3, 3] = (3.0, 0.0, 0.0)  # out of reach
    res = kin.ik_path(targets, q0, iterations=15)
    assert res.failed == 12 and res.iterations[12] == 15 and res.residual_pos[12] > 1.0
    assert np.isnan(res.q[13:]).all()
