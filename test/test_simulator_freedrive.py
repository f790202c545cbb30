"""Simulator.advance_free and the external wrench (pure, no ROS): gravity compensated, free under a push, the
limits still hold; position control resumes from the measured state."""
import mujoco
import numpy as np

from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

POSE = (0.3, -1.2, 1.0, -1.4, -1.2, 0.2)


def make(**params) -> Simulator:
    return Simulator(sim_config_from_params({'initial_positions': list(POSE), **params}))


def run_free(sim: Simulator, seconds: float) -> None:
    for _ in range(round(seconds / sim.control_dt)):
        sim.advance_free(sim.state())


def test_gravity_compensated_arm_stays():
    sim = make()
    run_free(sim, 1.0)
    assert np.abs(sim.state().q - POSE).max() < 1e-4


def push(sim, seconds: float) -> None:
    """Push wrist_3 sideways with 30 N for `seconds` [s] of free motion, then let go."""
    body = sim.physics.body_id('wrist_3_link')
    sim.physics.set_external_wrench(body, np.array([0.0, 30.0, 0.0]), np.zeros(3))
    run_free(sim, seconds)
    sim.physics.set_external_wrench(body, np.zeros(3), np.zeros(3))


def test_a_push_moves_it_and_the_damping_stops_it():
    sim = make()
    push(sim, 0.5)
    moved = np.abs(sim.state().q - POSE).max()
    assert moved > 0.05
    run_free(sim, 2.0)
    assert np.abs(sim.state().qd).max() < 0.01


def test_limits_hold_in_freedrive():
    sim = make()
    p = sim.params
    # Past a position limit, or faster than the velocity limit: the joint's full effort pushes back.
    q = np.array(POSE)
    q[5] = p.q_max[5] + 0.02
    sim.physics.reset(q)
    tau = sim.advance_free(sim.state())
    assert tau[5] < -0.9 * p.effort_max[5]
    sim = make()
    dof = sim.physics.model.jnt_dofadr[mujoco.mj_name2id(sim.physics.model, mujoco.mjtObj.mjOBJ_JOINT,
                                                          sim.physics.joint_names[4])]
    sim.physics.data.qvel[dof] = -(p.v_max[4] + 0.1)
    mujoco.mj_step1(sim.physics.model, sim.physics.data)
    tau = sim.advance_free(sim.state())
    assert tau[4] > 0.9 * p.effort_max[4]
    # Within the limits nothing of that: gravity compensation and damping only.
    sim = make()
    assert np.all(np.abs(sim.advance_free(sim.state())) < 0.9 * p.effort_max)


def test_position_control_resumes_without_a_jump():
    sim = make()
    push(sim, 0.3)
    run_free(sim, 1.5)  # the damping slows it
    q = sim.state().q
    zero = np.zeros(6)
    for _ in range(round(1.0 / sim.control_dt)):
        sim.advance(sim.state(), TrajectorySample(q, zero, zero, 0, True), q)
    # The servo starts from the measured state: it stops near where freedrive ended, and holds.
    assert np.abs(sim.state().qd).max() < 1e-3
    assert np.abs(sim.state().q - q).max() < 5e-3
