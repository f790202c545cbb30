"""The robot's torque control without ROS (Simulator.advance_torque, robot/direct_torque.py): gravity compensated
with the believed payload, the friction the compensation scales leave, the effort limits, the safety checks on the
measured motion, and the servo's modes afterwards."""
import numpy as np

from ur_sim_driver.robot.direct_torque import DEFAULT_SCALES, FrictionScales, felt_friction
from ur_sim_driver.robot.safety import motion_limit_cause
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

POSE = (0.3, -1.2, 1.0, -1.4, -1.2, 0.2)
JOINTS = tuple(f'j{i}' for i in range(6))


def make(**params) -> Simulator:
    return Simulator(sim_config_from_params({'initial_positions': list(POSE), **params}))


def run(sim: Simulator, torques, seconds: float) -> None:
    for _ in range(round(seconds / sim.control_dt)):
        sim.advance_torque(sim.state(), np.asarray(torques, dtype=float))


def wrist_3(torque: float) -> np.ndarray:
    return np.array([0.0, 0.0, 0.0, 0.0, 0.0, torque])


def test_zero_torques_hold_the_arm_where_it_is():
    sim = make()
    run(sim, np.zeros(6), 1.0)
    assert np.abs(sim.state().q - POSE).max() < 1e-4


def test_the_right_payload_belief_holds_a_mounted_payload_and_a_wrong_one_lets_it_drift():
    payload = {'mounted_payload.mass': 3.0, 'mounted_payload.cog': [0.0, 0.02, 0.08]}
    right = make(**payload)
    right.set_payload(3.0, np.array([0.0, 0.02, 0.08]), np.zeros(6))
    run(right, np.zeros(6), 1.0)
    assert np.abs(right.state().q - POSE).max() < 1e-4
    # Believed but not mounted: the compensation lifts what is not there, and the arm rises.
    wrong = make()
    wrong.set_payload(3.0, np.array([0.0, 0.02, 0.08]), np.zeros(6))
    z0 = wrong.tcp_pose()[0][2]
    run(wrong, np.zeros(6), 0.5)
    assert wrong.tcp_pose()[0][2] - z0 > 0.005


def test_coulomb_friction_holds_a_small_torque_unless_compensated():
    torque = wrist_3(0.3)  # [N m] wrist_3 of a ur5e: Coulomb friction 0.56 N m
    stuck = make()
    stuck.friction_scales = FrictionScales.make(DEFAULT_SCALES.viscous, np.zeros(6))
    run(stuck, torque, 0.5)
    assert abs(stuck.state().q[5] - POSE[5]) < 1e-4
    free = make()  # the defaults compensate 80 %: 0.11 N m left
    run(free, torque, 0.5)
    assert free.state().q[5] - POSE[5] > 0.01


def test_viscous_compensation_lets_the_joint_run_faster():
    speeds = {}
    for scale in (0.0, 1.0):
        sim = make()
        sim.friction_scales = FrictionScales.make(np.full(6, scale), np.ones(6))
        run(sim, wrist_3(0.06), 1.0)
        speeds[scale] = sim.state().qd[5]
    damping = sim.params.damping[5]
    assert 0.0 < speeds[0.0] <= 0.06 / damping  # below the terminal speed torque / damping
    assert speeds[1.0] > 1.2 * speeds[0.0]


def test_torques_stay_within_the_effort_limits():
    sim = make()
    tau = sim.advance_torque(sim.state(), np.full(6, -1e4))
    effort = sim.params.effort_max
    # The heavy joints at their limit; the light wrist_3 less: that much would take it past its speed limit.
    assert np.allclose(tau[:5], -effort[:5]) and -effort[5] < tau[5] < 0.0


def test_the_servo_resumes_from_the_measured_state_without_coulomb_friction():
    sim = make()
    run(sim, wrist_3(0.2), 0.2)
    assert sim.physics.model.dof_frictionloss.max() > 0.0
    state = sim.state()
    assert 0.1 < state.qd[5] < sim.params.v_max[5]
    zero = np.zeros(6)

    class Hold:
        positions, velocities, accelerations = state.q, zero, zero

    for _ in range(500):
        sim.advance(sim.state(), Hold)
    assert sim.physics.model.dof_frictionloss.max() == 0.0
    assert np.allclose(sim.physics.model.dof_damping[:6], sim.params.damping)
    assert np.abs(sim.state().qd).max() < 1e-3


def test_felt_friction_is_what_the_compensation_leaves():
    damping, coulomb = np.full(6, 2.0), np.full(6, 4.0)
    v, c = felt_friction(damping, coulomb, FrictionScales.make([0.0, 0.5, 1.0, 2.0, -1.0, 0.9], np.ones(6)))
    assert np.allclose(v, [2.0, 1.0, 0.0, 0.0, 2.0, 0.2]) and np.allclose(c, 0.0)  # scales clamped to [0, 1]


def test_no_joint_is_driven_past_its_speed_limit():
    sim = make()
    v_max = sim.params.v_max[5]
    speeds = []
    for _ in range(500):
        sim.advance_torque(sim.state(), wrist_3(5.0))  # 5 N m accelerates wrist_3 at over 300 rad/s^2
        speeds.append(sim.state().qd[5])
    assert max(speeds) <= v_max and speeds[-1] > 0.98 * v_max


def test_motion_limit_cause():
    lo, hi, a = np.full(6, -1.0), np.full(6, 1.0), np.full(6, 5.0)
    q, qd = np.zeros(6), np.zeros(6)
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS) is None
    # 1.5 rad/s stops within 0.225 rad at 5 rad/s^2: from 0.7 it stays inside, from 0.8 it would not.
    qd[1] = 1.5
    q[1] = 0.7
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS) is None
    q[1] = 0.8
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS) == \
        'j1 would pass its position limit 1.0000 rad (position 0.8000 rad, 1.500 rad/s)'
    qd[1] = -1.5  # moving away from it, or at rest at it: no stop
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS) is None
    q[1], qd[1] = 1.0, 0.0
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS) is None
    q[2], qd[2] = -0.9, -1.0  # towards the lower one
    assert motion_limit_cause(q, qd, lo, hi, a, JOINTS).startswith('j2 would pass its position limit -1.0000')
