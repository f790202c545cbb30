"""What the simulated robot feels of its contacts, checked against MuJoCo's own full steps (no ROS).

Every control cycle ur_sim reports the contacts of the robot and the flange's wrench; both must be the forces of
the physics steps that cycle completed, averaged over them. The reference here steps a copy of the same state with
``mj_step``, after which MuJoCo's contacts and constraint forces are those of the step it just took, and sums the
contact forces per pair of bodies itself.
"""
from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.touch import touch_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import tool_axis
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.simulator import Simulator

# [N m] on top of gravity compensation: shoulder and elbow press the nozzle on into the glass
PUSH = np.array([0.0, -2.0, -2.0, 0.0, 0.0, 0.0])





def _label(m: mujoco.MjModel, geom: int) -> str:
    body = int(m.geom_bodyid[geom])
    if body != 0:
        return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, body)
    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, geom) or f'geom {geom}'


def _reference_step(m: mujoco.MjModel, d: mujoco.MjData, robot_root: int, substeps: int):
    """Step `d` `substeps` times with mj_step; the robot's contact force per pair (robot body, other), summed over
    the pair's contacts and averaged over the steps [N], and the flange sensors' mean reading (6,)."""
    forces: dict[tuple[str, str], np.ndarray] = {}
    sensors = np.zeros(6)
    f6 = np.zeros(6)
    for _ in range(substeps):
        mujoco.mj_step(m, d)
        sensors += d.sensordata[:6]
        for i in range(d.ncon):
            c = d.contact[i]
            robot = [m.body_rootid[m.geom_bodyid[g]] == robot_root for g in (c.geom1, c.geom2)]
            if not any(robot):
                continue
            mujoco.mj_contactForce(m, d, i, f6)
            world = f6[0] * c.frame[0:3] + f6[1] * c.frame[3:6] + f6[2] * c.frame[6:9]
            pair = (_label(m, c.geom1), _label(m, c.geom2)) if robot[0] else (_label(m, c.geom2), _label(m, c.geom1))
            forces[pair] = forces.get(pair, np.zeros(3)) + world
    return {pair: float(np.linalg.norm(f)) / substeps for pair, f in forces.items()}, sensors / substeps


@pytest.fixture(scope='module')
def pressed():
    """Joint positions with the dispenser's nozzle pressed into the windshield (UR5e), found along a touch move."""
    job = dataclasses.replace(load_job(default_job_path()), ur_type='ur5e')
    sim = Simulator(SimConfig(ur_type='ur5e', tool='dispenser', scene='windshield'))
    kin = ur_kinematics(job.ur_type, job.tool)
    seg = touch_move(kin, plan_job(job, sim.state().q).bead.q[0], tool_axis(job.tool), height=0.005, depth=0.01,
                     speed=0.01, dt=job.sample_time)
    m, d = sim.physics.model, sim.physics.data
    robot_root = int(m.body_rootid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, 'base')])
    for q in seg.q:
        sim.physics.reset(q)
        if any(m.body_rootid[m.geom_bodyid[g]] == robot_root for c in d.contact[:d.ncon] for g in (c.geom1, c.geom2)):
            return q
    pytest.fail('the touch move never brings the nozzle into the glass')


@pytest.mark.parametrize('substeps', [1, 3])
def test_contacts_and_wrench_are_those_of_the_completed_physics_steps(pressed, substeps):
    sim = Simulator(SimConfig(ur_type='ur5e', tool='dispenser', scene='windshield', physics_substeps=substeps,
                              initial_positions=tuple(pressed)))
    m, d = sim.physics.model, sim.physics.data
    robot_root = int(m.body_rootid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, 'base')])
    reference = mujoco.MjData(m)
    seen = 0
    for _ in range(20):
        _, bias = sim.physics.dynamics()
        tau = bias + PUSH
        mujoco.mj_copyData(reference, m, d)
        reference.ctrl[:6] = tau
        expected, sensors = _reference_step(m, reference, robot_root, substeps)
        sim.physics.step(tau)
        found = {(c.robot_part, c.other): c.force for c in sim.physics.contacts()}
        assert found.keys() == expected.keys()
        for pair, force in expected.items():
            assert found[pair] == pytest.approx(force, rel=1e-9, abs=1e-9), pair
        seen += bool(expected)
        # The flange's force-torque sensor: what tool and contacts exert on the arm (the sensors' opposite).
        np.testing.assert_allclose(sim.physics.wrench(), -sensors, rtol=1e-9, atol=1e-9)
    assert seen >= 10  # the nozzle stayed on the glass for most of the cycles
