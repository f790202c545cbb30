"""Choice of the IK branch the bead is laid in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.ik_branch import _near, choose_branch, follow, start_branches
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rotation_angle, rotation_from_zyx_euler
from ur_glue_planner.path.glue_path import build_glue_path
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])
R_SEED = rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX)


@pytest.fixture(scope="module")
def kin():
    return ur_kinematics("ur5", "dispenser")


@pytest.fixture(scope="module")
def seed_path():
    # the seed's bead as MATLAB runs it: open, starting at the first clicked waypoint
    return build_glue_path(DEFAULT_WAYPOINTS, R_SEED, max_deviation=0.02)


@pytest.fixture(scope="module")
def choice(kin, seed_path):
    return choose_branch(seed_path, kin, HOME, 0.15)


def test_all_branches_reach_the_bead_start(kin, seed_path):
    target = np.eye(4)
    target[:3, :3], target[:3, 3] = R_SEED, DEFAULT_WAYPOINTS[0]
    qs = start_branches(kin, target, HOME, n_random=16)
    assert 4 <= len(qs) <= 8  # a 6R UR has up to eight
    for q in qs:
        t = kin.fk(q)
        assert np.linalg.norm(t[:3, 3] - DEFAULT_WAYPOINTS[0]) < 1e-6 and rotation_angle(t[:3, :3], R_SEED) < 1e-6
    wrapped = [np.mod(q + math.pi, 2 * math.pi) for q in qs]
    for i in range(len(qs)):
        for j in range(i):
            assert np.abs(wrapped[i] - wrapped[j]).max() > 1e-3


def test_home_branch_fails_and_a_wrist_flipped_branch_is_chosen(choice, kin, seed_path):
    best, branches = choice
    from_home = branches[0]  # the reference guess is tried first
    assert not from_home.feasible and "IK fails" in from_home.reason
    assert best.feasible and best.q[4] > 0.0  # only wrist-flipped branches reach the top edge
    ok, peak, why = follow(seed_path, kin, best.q, 0.15)
    assert ok and why == "" and peak == pytest.approx(best.peak_usage)
    assert 0.0 < best.peak_usage < 1.0


def test_the_nearest_of_the_best_branches_wins(choice):
    best, branches = choice
    good = [b for b in branches if b.feasible]
    assert len(good) >= 2
    peers = [b for b in good if b.peak_usage <= min(g.peak_usage for g in good) * 1.05]
    assert best.distance == min(b.distance for b in peers)
    assert best.distance == pytest.approx(np.linalg.norm(best.q - HOME))
    assert best.q[1] > -math.pi / 2 - 0.5  # the upper arm up (elbow-up), not reaching backwards


def test_near_shifts_by_whole_turns_within_limits():
    q_min, q_max = np.full(3, -2 * math.pi), np.full(3, 2 * math.pi)
    q = np.array([3.0, -3.0, 6.0])
    out = _near(q, np.array([-3.0, 3.0, 0.0]), q_min, q_max)
    np.testing.assert_allclose(out, [3.0 - 2 * math.pi, -3.0 + 2 * math.pi, 6.0 - 2 * math.pi])


def test_an_unreachable_bead_raises(kin):
    far = build_glue_path(np.array([[2.0, 0.0, 0.3], [2.2, 0.0, 0.3]]), R_SEED)
    with pytest.raises(PlanningError, match="out of reach"):
        choose_branch(far, kin, HOME, 0.15)


def test_the_closed_form_choice_equals_the_random_restart_newton_choice(choice, seed_path):
    # the same arm without the closed form: start branches from random guesses, followed by Newton
    tool = get_tool("dispenser")
    newton = Kinematics(build_urdf(load_ur_params("ur5"), tool=tool), joint_names(), tool.tip_name)
    best, branches = choice
    slow_best, slow_branches = choose_branch(seed_path, newton, HOME, 0.15)
    np.testing.assert_allclose(best.q, slow_best.q, atol=1e-4)
    assert best.peak_usage == pytest.approx(slow_best.peak_usage, rel=1e-3)
    # every branch the random restarts found is among the closed-form ones, equally judged
    for b in slow_branches:
        twin = min(branches, key=lambda c: np.abs(c.q - b.q).max())
        np.testing.assert_allclose(twin.q, b.q, atol=1e-4)
        assert twin.feasible == b.feasible
        if b.feasible:
            assert twin.peak_usage == pytest.approx(b.peak_usage, rel=1e-3)
