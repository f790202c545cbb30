"""The bead in joint space: IK per sample, exact velocities/accelerations, limits, slowdowns."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_common.quaternions import quat_from_matrix
from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.joint_trajectory import build_joint_plan, orientation_rates
from ur_glue_planner.motion.kinematics import IkResult, Kinematics
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rot_x, rot_z, rotation_angle, rotation_from_zyx_euler
from ur_glue_planner.path.glue_path import build_glue_path
from ur_glue_planner.path.timing import time_path
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

V, DT = 0.15, 0.02
A_MAX = 5.0  # DESIGN 5: ur_moveit_config's conservative acceleration limit
# An elbow-up, wrist-flipped configuration at the seed's first waypoint (found by random-restart
# IK while exploring; the branch test shows why the home pose itself does not work)
Q_START = np.array([-0.4, -1.52, -2.0, -0.98, 1.09, 1.12])
HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def kin() -> Kinematics:
    return ur_kinematics("ur5", "dispenser")


@pytest.fixture(scope="module")
def path():
    return build_glue_path(DEFAULT_WAYPOINTS, rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX),
                           max_deviation=0.02, closed=True)


@pytest.fixture(scope="module")
def plan(kin, path):
    return build_joint_plan(path, time_path(path.length, V, DT, ramp_time=0.3), kin, Q_START, a_max=A_MAX)


def length_fraction(s: np.ndarray, ok: np.ndarray) -> float:
    ds = np.diff(s)
    return float(ds[ok[1:] & ok[:-1]].sum() / ds.sum())


def test_every_sample_reaches_its_path_pose(plan, kin, path):
    assert plan.ik_residual_pos.max() < 1e-6 and plan.ik_residual_rot.max() < 1e-6
    pos, _, _ = path.sample(plan.s)
    rot = path.orientation(plan.s)
    for k in range(0, len(plan.s), 7):
        t = kin.fk(plan.q[k])
        assert np.linalg.norm(t[:3, 3] - pos[k]) < 1e-6
        assert rotation_angle(t[:3, :3], rot[k]) < 1e-6
    np.testing.assert_allclose(plan.tip_pos, pos, atol=1e-6)
    assert np.all(np.abs(np.abs(np.sum(plan.tip_quat * quat_from_matrix(rot), axis=1)) - 1.0) < 1e-9)


def test_tip_speed_from_forward_kinematics_is_constant_over_95_percent(plan, kin):
    tip = np.array([kin.fk(q)[:3, 3] for q in plan.q])
    chord_speed = np.linalg.norm(np.diff(tip, axis=0), axis=1) / np.diff(plan.times)
    ok = np.abs(chord_speed - V) <= 0.01 * V
    ds = np.diff(plan.s)
    assert ds[ok].sum() / ds.sum() >= 0.95
    # and the planned speed |J qd| agrees
    assert length_fraction(plan.s, np.abs(plan.tcp_speed - V) <= 0.01 * V) >= 0.95
    assert plan.tcp_speed.max() <= V * 1.001


def test_velocities_and_accelerations_integrate_to_the_positions(plan):
    dt = np.diff(plan.times)[:, None]
    # trapezoid rule: O(dt^3) per step where q is smooth; the curvature steps at the arc ends
    # (where qdd jumps) are the only larger ones
    pos_err = np.abs(np.diff(plan.q, axis=0) - dt * (plan.qd[1:] + plan.qd[:-1]) / 2).max(axis=1)
    vel_err = np.abs(np.diff(plan.qd, axis=0) - dt * (plan.qdd[1:] + plan.qdd[:-1]) / 2).max(axis=1)
    assert pos_err.max() < 5e-4 and np.percentile(pos_err, 95) < 3e-5
    assert vel_err.max() < 0.05 and np.percentile(vel_err, 95) < 1e-3


def test_path_derivatives_are_consistent_with_the_time_law(plan):
    t = plan.timing
    np.testing.assert_allclose(plan.qd, plan.q_s * t.sdot[:, None], atol=1e-12)
    np.testing.assert_allclose(plan.qdd, plan.q_s * t.sddot[:, None] + plan.q_ss * t.sdot[:, None] ** 2, atol=1e-12)


def test_joint_limits_hold_everywhere(plan, kin):
    assert np.all(np.abs(plan.qd) <= 0.95 * kin.v_max + 1e-9)
    assert np.abs(plan.qdd).max() <= A_MAX + 1e-9
    assert np.all(plan.q >= kin.q_min) and np.all(plan.q <= kin.q_max)
    step = np.abs(np.diff(plan.q, axis=0))
    assert np.all(step <= kin.v_max * DT)  # continuity: no branch change


def test_the_top_left_corner_is_slowed_down_for_the_elbow(plan, path):
    # the seed's top-left corner (waypoint 5) is near the arm's reach: at 0.15 m/s its arc
    # would need ~6 rad/s^2 at the elbow
    assert len(plan.slowdowns) >= 1
    sd = plan.slowdowns[0]
    assert sd.joint == "elbow_joint" and sd.kind == "acceleration" and sd.demand > A_MAX
    corner = next(c for c in path.corners if c.waypoint == 5)
    assert sd.s_start < 0.5 * (corner.s_start + corner.s_end) < sd.s_end
    inside = (plan.s >= sd.s_start) & (plan.s <= sd.s_end)
    assert plan.tcp_speed[inside].max() <= sd.factor * V * (1 + 1e-9)
    assert 0.7 < sd.factor < 1.0
    assert plan.retimes >= 1


def test_ik_of_all_samples_needs_no_newton_step(plan):
    # the closed form meets 1e-6 m/rad without a Newton step (only the first sample starts from the guess); its
    # wall time is bench_planner's (`make bench`: planning.ik_all_samples_ms)
    assert np.mean(plan.ik_iterations) < 1.0


def test_a_velocity_limit_is_met_by_slowing_down(kin, path):
    v_max = np.full(6, 0.6)  # [rad/s] far below the UR5's: the elbow (~0.95 rad/s) must slow down
    plan = build_joint_plan(path, time_path(path.length, V, DT, ramp_time=0.3), kin, Q_START, v_max=v_max)
    assert any(sd.kind == "velocity" and sd.joint == "elbow_joint" for sd in plan.slowdowns)
    assert np.abs(plan.qd).max() <= 0.95 * 0.6 + 1e-9
    assert plan.times[-1] > path.length / V + 0.3


def test_leaving_the_workspace_fails_naming_sample_and_waypoint(kin):
    # a straight bead from the seed's first waypoint out to 1.2 m: beyond a UR5's reach
    start = DEFAULT_WAYPOINTS[0]
    far = build_glue_path(np.array([start, start + [0.0, 0.4, 0.0], start + [0.0, 0.8, 0.0]]),
                          rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX))
    with pytest.raises(PlanningError, match=r"IK failed at sample \d+ \(s = 0\.[3-7]\d* m .*nearest waypoint [12]\)"):
        build_joint_plan(far, time_path(far.length, V, DT), kin, Q_START)


def test_from_home_the_seed_first_waypoint_lands_in_a_branch_that_cannot_follow(kin):
    # why the planner chooses branches (ik_branch): warm-started IK never changes branch
    open_path = build_glue_path(DEFAULT_WAYPOINTS, rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX),
                                max_deviation=0.01)
    with pytest.raises(PlanningError, match=r"IK failed at sample \d+ .*nearest waypoint [2-6]\)"):
        build_joint_plan(open_path, time_path(open_path.length, V, DT), kin, HOME)


class _FlippingKinematics(Kinematics):
    """Adds a full turn to wrist 3 after a number of IK calls: same pose, a joint-space jump."""

    flip_after = 50

    def ik(self, *args, **kwargs) -> IkResult:
        res = super().ik(*args, **kwargs)
        self.calls = getattr(self, "calls", 0) + 1
        if self.calls > self.flip_after:
            q = res.q.copy()
            q[5] += 2 * math.pi
            return IkResult(q, res.residual_pos, res.residual_rot, res.iterations, res.converged)
        return res


def test_a_jump_between_samples_names_the_joint_and_sample(kin, path):
    flipping = _FlippingKinematics.__new__(_FlippingKinematics)
    flipping.__dict__.update(kin.__dict__)
    with pytest.raises(PlanningError, match=r"wrist_3_joint jumps 6\.2[78].* samples 49 and 50 .*nearest waypoint"):
        build_joint_plan(path, time_path(path.length, V, DT), flipping, Q_START)


def test_orientation_rates_of_a_single_slerp_are_constant():
    # two keys 90 deg apart about z over a 0.5 m straight line: w_s = pi/2 / 0.5 rad/m about z
    r0, r1 = rot_x(math.pi), rot_z(math.pi / 2) @ rot_x(math.pi)
    line = build_glue_path(np.array([[0.3, 0.2, 0.3], [0.3, 0.7, 0.3]]), np.array([r0, r1]))
    w_s, dw_s = orientation_rates(line, np.linspace(0.0, 0.5, 11))
    np.testing.assert_allclose(w_s, np.tile([0.0, 0.0, math.pi / 2 / 0.5], (11, 1)), atol=1e-9)
    np.testing.assert_allclose(dw_s, 0.0, atol=1e-5)


def test_angular_velocity_of_a_turning_tool_is_exact(kin):
    # the tool turns 30 deg about the world z while moving 0.2 m: the Jacobian twist of the
    # planned qd must match finite differences of the planned orientations
    start = kin.fk(Q_START)
    r0 = start[:3, :3]
    r1 = rot_z(math.radians(30)) @ r0
    p0 = start[:3, 3]
    line = build_glue_path(np.array([p0, p0 + [0.2, 0.0, 0.0]]), np.array([r0, r1]))
    plan = build_joint_plan(line, time_path(line.length, 0.1, DT, ramp_time=0.3), kin, Q_START)
    omega = np.array([kin.jacobian(q)[3:] @ qd for q, qd in zip(plan.q, plan.qd)])
    rot = np.array([kin.fk(q)[:3, :3] for q in plan.q])
    k = len(plan.q) // 2
    d = (rot[k + 1] - rot[k - 1]) / (2 * DT) @ rot[k].T
    np.testing.assert_allclose(omega[k], [d[2, 1], d[0, 2], d[1, 0]], atol=1e-4)
    np.testing.assert_allclose(omega[k], [0, 0, math.radians(30) / 0.2 * 0.1], atol=1e-6)


def test_the_closed_form_plan_equals_the_per_sample_newton_plan(plan, path):
    # the same arm without the closed-form IK (a plain Kinematics): every sample by warm-started Newton
    tool = get_tool("dispenser")
    newton = Kinematics(build_urdf(load_ur_params("ur5"), tool=tool), joint_names(), tool.tip_name)
    slow = build_joint_plan(path, time_path(path.length, V, DT, ramp_time=0.3), newton, Q_START, a_max=A_MAX)
    assert len(slow.times) == len(plan.times) and len(slow.slowdowns) == len(plan.slowdowns)
    np.testing.assert_allclose(slow.times, plan.times, atol=1e-6)
    np.testing.assert_allclose(slow.q, plan.q, atol=1e-4)  # Newton's own tolerance is 1e-6 m / rad
    np.testing.assert_allclose(slow.tcp_speed, plan.tcp_speed, rtol=1e-4)
    for a, b in zip(slow.slowdowns, plan.slowdowns):
        assert (a.joint, a.kind) == (b.joint, b.kind) and a.factor == pytest.approx(b.factor, rel=1e-4)
