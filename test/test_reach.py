"""motion/reach.py: a bead beyond a robot type's reach is refused before IK, with the reason."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.reach import envelope, flange_positions, reach_refusal
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import job_waypoints
from ur_sim_driver.description.params import UR_TYPES, load_ur_params
from ur_sim_driver.description.tool import DISPENSER

JOB_FILE = Path(__file__).resolve().parents[1] / "config" / "glue_job.yaml"


def test_flange_positions_are_the_forward_kinematics_of_tool0():
    tip, flange = ur_kinematics("ur5e", DISPENSER), ur_kinematics("ur5e", None)
    rng = np.random.default_rng(3)
    qs = rng.uniform(-3.0, 3.0, (20, 6))
    tips = np.array([tip.fk(q) for q in qs])
    expected = np.array([flange.fk(q)[:3, 3] for q in qs])
    np.testing.assert_allclose(flange_positions(tips[:, :3, 3], tips[:, :3, :3], DISPENSER), expected, atol=1e-12)
    np.testing.assert_array_equal(flange_positions(expected, tips[:, :3, :3], None), expected)


@pytest.mark.parametrize("ur_type", UR_TYPES)
def test_the_envelope_is_the_farthest_the_flange_gets(ur_type):
    """Random joint positions stay within the envelope, and a search over the arm's forward kinematics from
    several starts finds it (the farthest flange position, to 1e-6 m)."""
    robot = load_ur_params(ur_type)
    flange = ur_kinematics(robot, None)
    shoulder = np.array([0.0, 0.0, robot.dh.d1])

    def distance(q):
        return float(np.linalg.norm(flange.fk(q)[:3, 3] - shoulder))

    rng = np.random.default_rng(4)
    assert max(distance(q) for q in rng.uniform(-np.pi, np.pi, (500, 6))) <= envelope(robot)
    found = max(-minimize(lambda q: -distance(q), q0, method="Nelder-Mead",
                          options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000}).fun
                for q0 in rng.uniform(-np.pi, np.pi, (6, 6)))
    assert found == pytest.approx(envelope(robot), abs=1e-6) and found <= envelope(robot) + 1e-12


def test_a_point_just_beyond_the_envelope_is_refused_and_one_just_within_is_not():
    robot = load_ur_params("ur3e")
    shoulder = np.array([0.0, 0.0, robot.dh.d1])
    direction = np.array([0.6, 0.8, 0.0])
    rot = np.eye(3)[None]
    inside = shoulder + (envelope(robot) - 1e-6) * direction
    assert reach_refusal(inside[None], rot, robot, None) is None
    outside = shoulder + (envelope(robot) + 1e-3) * direction
    text = reach_refusal(np.vstack([inside, outside]), np.repeat(rot, 2, axis=0), robot, None)
    assert f"never more than {envelope(robot):.3f} m from its shoulder (data-sheet reach 0.500 m)" in text
    assert f"{envelope(robot) + 1e-3:.3f} m away at waypoint 1" in text


@pytest.mark.timeout(120)
def test_the_windshield_job_on_a_ur3_is_refused_with_the_reason():
    job = load_job(JOB_FILE)
    small = dataclasses.replace(job, ur_type="ur3")
    with pytest.raises(PlanningError) as info:
        plan_job(small, np.array(job.home))
    assert "'ur3' cannot reach the bead" in str(info.value) and "longer reach" in str(info.value)
    points, rots = job_waypoints(job)
    assert reach_refusal(points, rots, load_ur_params(job.ur_type), DISPENSER) is None
