"""UrKinematics: path IK in closed form, checked and refined by Pinocchio, equal to per-sample Newton."""

from __future__ import annotations

import numpy as np
import pytest

from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.motion.ur_arm_kinematics import NotOnFlangeError, UrKinematics, ur_kinematics
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.path.glue_path import build_glue_path
from ur_sim_driver.description.params import DH, joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

# Newton stops within 1e-6 m / 1e-6 rad, so its joints differ from the exact ones by up to ~1e-5 rad where the
# arm is near-stretched; other branches differ by tenths of a radian
SAME = 1e-4
Q_START = np.array([-0.4, -1.52, -2.0, -0.98, 1.09, 1.12])  # elbow up, wrist flipped, at the seed's bead start
HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def kin() -> UrKinematics:
    return ur_kinematics("ur5", "dispenser")


@pytest.fixture(scope="module")
def newton() -> Kinematics:
    """The same arm without the closed form: per-sample Newton."""
    tool = get_tool("dispenser")
    return Kinematics(build_urdf(load_ur_params("ur5"), tool=tool), joint_names(), tool.tip_name)


def bead_poses(closed: bool = True, step: float = 0.003) -> np.ndarray:
    path = build_glue_path(DEFAULT_WAYPOINTS, rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX),
                           max_deviation=0.02, closed=closed)
    s = np.arange(0.0, path.length, step)
    out = np.zeros((len(s), 4, 4))
    out[:, :3, :3], out[:, :3, 3], out[:, 3, 3] = path.orientation(s), path.sample(s)[0], 1.0
    return out


def test_flange_frames_get_the_closed_form_and_others_do_not():
    assert isinstance(ur_kinematics("ur5e", "dispenser"), UrKinematics)
    assert isinstance(ur_kinematics("ur10", None), UrKinematics)
    assert isinstance(ur_kinematics("ur10e", "dispenser", frame="tool0"), UrKinematics)
    assert isinstance(ur_kinematics("ur5", "dispenser", frame="flange", tf_prefix="left_"), UrKinematics)
    other = ur_kinematics("ur5", "dispenser", frame="forearm_link")
    assert type(other) is Kinematics
    with pytest.raises(NotOnFlangeError, match="forearm_link"):
        UrKinematics(build_urdf(load_ur_params("ur5")), joint_names(), "forearm_link", load_ur_params("ur5").dh)


def test_a_urdf_that_is_not_the_dh_arm_is_refused():
    params = load_ur_params("ur5")
    other = DH(**{**params.dh.__dict__, "a3": params.dh.a3 - 0.01})
    with pytest.raises(ValueError, match="differs from the closed form"):
        UrKinematics(build_urdf(params), joint_names(), "tool0", other)


def test_path_ik_equals_per_sample_newton_on_the_bead(kin, newton):
    targets = bead_poses()
    fast = kin.ik_path(targets, Q_START)
    slow = newton.ik_path(targets, Q_START)
    assert fast.failed is None and slow.failed is None
    np.testing.assert_allclose(fast.q, slow.q, atol=SAME)
    assert fast.residual_pos[0] < 1e-6 and fast.residual_rot[0] < 1e-6  # the first pose: Newton from Q_START
    assert fast.residual_pos[1:].max() < 1e-12 and fast.residual_rot[1:].max() < 1e-12  # the others: exact
    assert np.all(fast.iterations[1:] == 0)
    # the FK and Jacobians it hands back are Pinocchio's at q
    for k in (0, len(targets) // 2, len(targets) - 1):
        p, r, jac = kin.fk_jacobian(fast.q[k])
        np.testing.assert_allclose(fast.position[k], p, atol=1e-15)
        np.testing.assert_allclose(fast.rotation[k], r, atol=1e-15)
        np.testing.assert_allclose(fast.jacobian[k], jac, atol=1e-15)


def test_the_branch_is_the_one_newton_lands_in_from_q0(kin, newton):
    targets = bead_poses()[:40]
    for q0 in (Q_START, HOME, np.array([1.0, -2.0, 2.0, 0.5, -1.0, 2.5])):
        fast, slow = kin.ik_path(targets, q0), newton.ik_path(targets, q0)
        assert (fast.failed is None) == (slow.failed is None)
        n = len(targets) if fast.failed is None else fast.failed
        np.testing.assert_allclose(fast.q[:n], slow.q[:n], atol=SAME)


def test_a_branch_leaving_the_workspace_fails_where_newton_does(kin, newton):
    # from home the seed's first waypoint lands in a branch that cannot reach the top edge
    targets = bead_poses(closed=False)
    fast, slow = kin.ik_path(targets, HOME), newton.ik_path(targets, HOME)
    assert fast.failed is not None and slow.failed is not None
    assert abs(fast.failed - slow.failed) <= 1
    assert fast.residual_pos[fast.failed] > 1e-6 or fast.residual_rot[fast.failed] > 1e-6
    np.testing.assert_allclose(fast.q[:fast.failed - 1], slow.q[:fast.failed - 1], atol=SAME)


def test_an_unreachable_first_pose_fails_at_once(kin):
    target = np.eye(4)
    target[:3, 3] = (2.0, 0.0, 0.3)
    res = kin.ik_path(np.stack([target, target]), HOME, first_iterations=30)
    assert res.failed == 0 and res.iterations[0] == 30


def test_all_solutions_of_a_pose(kin):
    target = bead_poses()[0]
    sols = kin.ik_solutions(target)
    assert sols.shape == (8, 6)
    valid = sols[~np.isnan(sols).any(axis=1)]
    assert len(valid) >= 4
    for q in valid:
        np.testing.assert_allclose(kin.fk(q), target, atol=1e-9)
    gaps = [np.abs(a - b).max() for i, a in enumerate(valid) for b in valid[:i]]
    assert min(gaps) > 0.1  # eight different arm configurations


def test_a_moved_prefixed_arm_solves_in_its_world_frame():
    base = np.eye(4)
    base[:3, 3] = (0.0, 0.0, 1.0)  # seed 2's UR10 stands 1 m up
    kin = ur_kinematics("ur10", None, frame="ee_link", base_pose=base, tf_prefix="ur10_")
    newton = Kinematics(build_urdf(load_ur_params("ur10"), tf_prefix="ur10_"), joint_names("ur10_"), "ur10_ee_link",
                        base_pose=base)
    assert isinstance(kin, UrKinematics)
    q = np.array([-0.38, 0.98, -2.0, 2.22, 0.86, 1.33]) + np.linspace(0.0, 0.2, 25)[:, None]
    targets = np.array([newton.fk(x) for x in q])
    fast, slow = kin.ik_path(targets, q[0] + 0.05), newton.ik_path(targets, q[0] + 0.05)
    assert fast.failed is None and slow.failed is None
    np.testing.assert_allclose(fast.q, q, atol=SAME)
    np.testing.assert_allclose(slow.q, q, atol=SAME)
