"""motion/clearance.py and its use by the planner: the arm's own collision shapes (ur_sim's) keep a plan clear of
self-contact and of the floor."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.clearance import Clearance
from ur_glue_planner.motion.plan import plan_job
from ur_sim_driver.description.params import UR_TYPES, load_ur_params
from ur_sim_driver.description.tool import DISPENSER

JOB_FILE = Path(__file__).resolve().parents[1] / "config" / "glue_job.yaml"
HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])


@pytest.mark.parametrize("ur_type", UR_TYPES)
def test_home_is_clear_a_folded_elbow_touches_and_an_arm_through_the_floor_too(ur_type):
    clearance = Clearance(load_ur_params(ur_type), DISPENSER)
    assert clearance.first_touch(HOME) is None
    folded = HOME + [0.0, 0.0, math.radians(178.0), 0.0, 0.0, 0.0]
    touch = clearance.first_touch(np.vstack([HOME, folded]))
    assert touch is not None and touch.index == 1 and touch.depth > 0.0
    assert "the floor" not in touch.parts
    down = np.radians([0.0, 60.0, 0.0, 0.0, 0.0, 0.0])  # the stretched arm 60 deg below the horizontal
    touch = clearance.first_touch(down)
    assert touch is not None and "the floor" in touch.parts
    assert touch.describe().startswith(f"{touch.parts[0]} touches {touch.parts[1]} (")


def test_the_planner_lays_the_bead_in_a_branch_clear_of_the_arm_and_refuses_when_none_is():
    """On a UR15 the branch the joint-speed criterion alone prefers folds the elbow to -169 deg, where the wrist
    touches the upper arm; the planner takes a clear one, and a job forced into the touching one is refused."""
    job = dataclasses.replace(load_job(JOB_FILE), ur_type="ur15")
    plan = plan_job(job, np.array(job.home))
    clearance = Clearance(load_ur_params("ur15"), DISPENSER)
    for q in (plan.approach.q, plan.descent.q, plan.bead.q, plan.retreat.q):
        assert clearance.first_touch(q) is None
    folded = [b for b in plan.branches if "upper_arm_link touches wrist_1_link" in b.reason]
    assert folded and not folded[0].feasible, [b.reason for b in plan.branches]
    forced = dataclasses.replace(job, ik_seed=tuple(float(x) for x in folded[0].q))
    with pytest.raises(PlanningError, match=r"^(approach|descent|bead|retreat): .+ touches .+ at t = "):
        plan_job(forced, np.array(job.home))
