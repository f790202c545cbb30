"""tool_contact_controller over DDS on the windshield: with a ToolContact goal active, the dispenser tip moved onto
the glass stops within one control period of the first contact, without a protective stop, the goal succeeds and
the trajectory goal is aborted; without a goal the same move ends in a protective stop. Also upstream's goal
rules (inactive, busy, cancel, deactivation)."""
import dataclasses

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from control_msgs.action import FollowJointTrajectory
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import ready_action, running_sim, wait_for, wait_still
from ur_msgs.action import FollowJointTrajectoryUntil, ToolContact

from ur_common.action_client import ActionClient
from ur_glue_planner.execution.ros_conversions import joint_trajectory
from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.approach import joint_move
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.touch import touch_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import tool_axis
from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.physics.tool_contact import tool_bodies
from ur_sim_driver.robot.robot_state import NORMAL, PROTECTIVE_STOP

NAME = 'tool_contact_controller'
# [m/s] a touch-off speed: at 0.15 m/s the first contact step alone already exceeds the protective stop force
TOUCH_SPEED = 0.02


def goal_of(h, seg) -> FollowJointTrajectory.Goal:
    g = FollowJointTrajectory.Goal()
    g.trajectory = joint_trajectory(h.joints, seg.times, seg.q, seg.qd, seg.qdd)
    return g


class ToolContactClient:
    def __init__(self, h) -> None:
        self.client = ActionClient(h.client, ToolContact, f'/{NAME}/detect_tool_contact',
                                   callback_group=ReentrantCallbackGroup())
        ready_action(self.client, probe_goals=False)  # an empty ToolContact goal is a real request

    def send(self):
        future = self.client.send_goal_async(ToolContact.Goal())
        wait_still(future.done, what='the ToolContact goal response')
        return future.result()

    @staticmethod
    def status(handle, timeout: float = 30.0) -> int:
        future = handle.get_result_async()
        wait_for(future.done, timeout, 'the ToolContact result')
        return future.result().status


def test_cb3_refuses_the_controller():
    # First: its ur_sim shares the test process's domain, so it must be gone before the module's starts.
    with running_sim(ur_type='ur5') as h:
        cm = ControllerManagerClient(h)
        answer = cm.switch(activate=[NAME])
        assert not answer.ok
        assert cm.states()[NAME] == 'inactive'


@pytest.fixture(scope='module')
def scene():
    """The sim with the windshield, the arm above the first bead point, the touch move into the glass. Tool
    contact needs an e-Series robot (upstream refuses it on CB3): the job's UR5 becomes a UR5e."""
    job = dataclasses.replace(load_job(default_job_path()), ur_type='ur5e')
    with running_sim(ur_type=job.ur_type, tool='dispenser', scene='windshield') as h:
        plan = plan_job(job, h.q)
        kin = ur_kinematics(job.ur_type, job.tool)
        seg = touch_move(kin, plan.bead.q[0], tool_axis(job.tool), height=0.01, depth=0.01, speed=TOUCH_SPEED,
                         dt=job.sample_time)
        yield h, seg, ControllerManagerClient(h), ToolContactClient(h)


def move_to_start(h, seg) -> None:
    params = h.sim.sim.params
    move = joint_move(h.q, seg.q[0], params.v_max, params.a_max, 0.008, min_duration=2.0)
    handle = h.send(goal_of(h, move))
    assert handle.accepted
    assert h.result(handle, timeout=60)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)


def test_goal_rules(scene):
    h, seg, cm, tc = scene
    assert cm.controllers()[NAME].claimed_interfaces == []
    assert not tc.send().accepted  # inactive
    assert cm.switch(activate=[NAME], strictness=BEST_EFFORT).ok
    # It runs beside the trajectory controller: it claims only its own interface.
    states = cm.states()
    assert states[NAME] == 'active' and states['scaled_joint_trajectory_controller'] == 'active'
    assert cm.controllers()[NAME].claimed_interfaces == ['tool_contact/tool_contact_set_state']
    first = tc.send()
    assert first.accepted
    assert not tc.send().accepted  # busy
    future = first.cancel_goal_async()
    wait_for(future.done, what='the cancel answer')
    assert future.result().return_code == 0
    assert tc.status(first) == GoalStatus.STATUS_CANCELED
    again = tc.send()
    assert again.accepted
    assert cm.switch(deactivate=[NAME], strictness=BEST_EFFORT).ok
    assert tc.status(again) == GoalStatus.STATUS_ABORTED


def test_touching_the_glass_with_a_goal_stops_within_one_period_without_protective_stop(scene):
    h, seg, cm, tc = scene
    move_to_start(h, seg)
    assert cm.switch(activate=[NAME]).ok
    contact_goal = tc.send()
    assert contact_goal.accepted
    # Probes on the real simulation: every contact list it computes and every reference the robot's servo gets.
    sim = h.sim.sim
    tool = tool_bodies(sim.physics.model, 'wrist_3_link')
    contacts_at, references = [], []
    real_contacts, real_advance = sim.physics.contacts, sim.advance

    def contacts():
        found = real_contacts()
        contacts_at.append((sim.time, [c for c in found if c.robot_part in tool]))
        return found

    def advance(state, ref, stop=None):
        references.append((state.t, ref.velocities.copy()))
        return real_advance(state, ref, stop)

    with h.sim.host.lock:
        sim.physics.contacts, sim.advance = contacts, advance
    try:
        handle = h.send(goal_of(h, seg))
        assert handle.accepted
        status, code, text = h.result(handle)
        assert tc.status(contact_goal) == GoalStatus.STATUS_SUCCEEDED
        h.wait_sim_time(0.5)
    finally:
        with h.sim.host.lock:
            del sim.physics.contacts, sim.advance
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED)
    assert 'tool contact: dispenser touched windshield_piece_' in text, text
    assert h.sim.robot.safety_mode == NORMAL
    # The first contact that pushes (MuJoCo reports a new contact one step before its force acts).
    t_first = next(t for t, found in contacts_at if any(c.force > 0.0 for c in found))
    # The cycle that starts at the first contact already commands the robot to rest.
    t_ref, v_ref = next((t, v) for t, v in references if t >= t_first - 1e-9)
    assert t_ref == pytest.approx(t_first, abs=1e-9)
    assert np.abs(v_ref).max() == 0.0
    # Far below the protective stop's force all along, and at rest now.
    assert max(c.force for _, found in contacts_at for c in found) < h.sim.cfg.protective_stop_force
    q = h.q
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q).max() < 1e-3


def test_a_passthrough_trajectory_is_aborted_by_the_robot(scene):
    h, seg, cm, tc = scene
    move_to_start(h, seg)
    passthrough = 'passthrough_trajectory_controller'
    assert cm.switch(activate=[passthrough, NAME], deactivate=['scaled_joint_trajectory_controller']).ok
    client = ActionClient(h.client, FollowJointTrajectory, f'/{passthrough}/follow_joint_trajectory',
                          callback_group=ReentrantCallbackGroup())
    ready_action(client)
    contact_goal = tc.send()
    assert contact_goal.accepted
    handle = h.send(goal_of(h, seg), client=client)
    assert handle.accepted
    # Upstream's "aborted by hardware": status aborted, the result left empty.
    assert h.result(handle)[:2] == (GoalStatus.STATUS_ABORTED, 0)
    assert tc.status(contact_goal) == GoalStatus.STATUS_SUCCEEDED
    assert h.sim.robot.safety_mode == NORMAL
    assert cm.switch(activate=['scaled_joint_trajectory_controller'], deactivate=[passthrough]).ok


def test_without_a_goal_the_same_move_ends_in_a_protective_stop(scene):
    h, seg, cm, tc = scene
    move_to_start(h, seg)
    assert cm.switch(activate=[NAME]).ok  # active, but no goal: nothing watches the tool
    log = h.rosout()
    handle = h.send(goal_of(h, seg))
    assert handle.accepted
    status, code, text = h.result(handle)
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL)
    assert text == 'Current goal cancelled during deactivate transition.'
    wait_still(lambda: any('safety mode is PROTECTIVE_STOP' in m for _, m in log), what='the cause in the log')
    assert h.sim.robot.safety_mode == PROTECTIVE_STOP


@pytest.mark.parametrize('run', range(20))
def test_a_slow_approach_ends_in_tool_contact_never_in_a_protective_stop(scene, run):
    """Approaches at 5 to 50 mm/s from 3 to 12 mm above the glass, each started at another phase of the physics
    steps: the tool contact stops the arm every time, the safety system never does."""
    h, _, cm, tc = scene
    job = dataclasses.replace(load_job(default_job_path()), ur_type='ur5e')
    kin = ur_kinematics(job.ur_type, job.tool)
    speed = 0.005 + 0.045 * run / 19  # [m/s]
    height = 0.003 + 0.009 * ((run * 7) % 20) / 19  # [m] above the surface at the start
    seg = touch_move(kin, plan_job(job, h.q).bead.q[0], tool_axis(job.tool), height=height, depth=0.01,
                     speed=speed, dt=job.sample_time)
    move_to_start(h, seg)
    if cm.states()[NAME] != 'active':
        assert cm.switch(activate=[NAME], strictness=BEST_EFFORT).ok
    contact_goal = tc.send()
    assert contact_goal.accepted
    handle = h.send(goal_of(h, seg))
    assert handle.accepted
    status, code, text = h.result(handle)
    assert tc.status(contact_goal) == GoalStatus.STATUS_SUCCEEDED, text
    assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED), text
    assert 'tool contact: dispenser touched windshield_piece_' in text, text
    assert h.sim.robot.safety_mode == NORMAL, h.sim.robot.stop_cause
    h.wait_sim_time(0.3)
    q = h.q
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q).max() < 1e-4
    assert h.sim.robot.safety_mode == NORMAL, h.sim.robot.stop_cause


def test_trajectory_until_tool_contact_ends_the_touch_early(scene):
    """The driver's trajectory_until_node: the touch move with until TOOL_CONTACT ends triggered and successful."""
    h, seg, cm, tc = scene
    move_to_start(h, seg)
    assert cm.switch(activate=[NAME]).ok
    until = ActionClient(h.client, FollowJointTrajectoryUntil, '/trajectory_until_node/execute',
                         callback_group=ReentrantCallbackGroup())
    # (the client stays until the harness's client node goes, after its executor stopped)
    ready_action(until, probe_goals=False)
    goal = FollowJointTrajectoryUntil.Goal(trajectory=goal_of(h, seg).trajectory,
                                           until_type=FollowJointTrajectoryUntil.Goal.TOOL_CONTACT)
    future = until.send_goal_async(goal)
    wait_still(future.done, timeout=30.0, what='the until goal answer')
    handle = future.result()
    assert handle.accepted
    result_future = handle.get_result_async()
    wait_for(result_future.done, 30.0, 'the until result')
    result = result_future.result()
    assert result.status == GoalStatus.STATUS_SUCCEEDED
    assert result.result.until_condition_result == FollowJointTrajectoryUntil.Result.TRIGGERED
    assert result.result.error_code == FollowJointTrajectoryUntil.Result.SUCCESSFUL
    assert h.sim.robot.safety_mode == NORMAL
