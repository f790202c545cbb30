"""The two trajectory controllers over DDS: joint_trajectory_controller ignores the robot's speed scaling where
the scaled one follows it; both answer ~/query_state."""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTrajectoryControllerState, SpeedScalingFactor
from control_msgs.srv import QueryTrajectoryState
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import following, point, ready_action, running_sim, wait_answer, wait_for, wait_still
from ur_msgs.srv import SetSpeedSliderFraction

from ur_common.action_client import ActionClient
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion import result_codes as rc

SCALED, JTC = 'scaled_joint_trajectory_controller', 'joint_trajectory_controller'
ZERO = [0.0] * 6


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.cm = ControllerManagerClient(h)
        group = ReentrantCallbackGroup()
        h.actions = {SCALED: h.action, JTC: ActionClient(h.client, FollowJointTrajectory,
                                                         f'/{JTC}/follow_joint_trajectory', callback_group=group)}
        h.query = {name: h.client.create_client(QueryTrajectoryState, f'/{name}/query_state', callback_group=group)
                   for name in (SCALED, JTC)}
        ready_action(h.actions[JTC])
        for client in h.query.values():
            wait_still(client.service_is_ready, what='query_state')
        yield h


def _run(h, name, goal):
    handle = h.send(goal, client=h.actions[name])
    assert handle.accepted
    return handle


def _query(h, name, t):
    return wait_answer(h.query[name].call_async(QueryTrajectoryState.Request(time=h.sim.clock.stamp(t))),
                       'query_state')


def test_one_rad_in_half_a_second_scaled_slows_down_unscaled_violates_the_path(robot):
    h = robot
    h.cm.switch(activate=[SCALED], deactivate=[JTC], strictness=BEST_EFFORT)
    q0 = h.q
    scaling: list[float] = []
    h.record()
    handle = _run(h, SCALED, h.goal([point(q0 - 1.0, 0.5)]))
    assert h.result(handle)[:2] == (GoalStatus.STATUS_SUCCEEDED, rc.SUCCESSFUL)
    scaling = h.stop_recording().speed_scaling
    assert min(scaling) < 90.0  # the robot slowed itself, and the scaled controller waited for it
    assert h.cm.switch(activate=[JTC], deactivate=[SCALED]).ok
    states: list[float] = []
    stop = h.listen(JointTrajectoryControllerState, f'/{JTC}/controller_state',
                    lambda m: states.append(m.speed_scaling_factor), depth=10)
    try:
        handle = _run(h, JTC, h.goal([point(h.q + 1.0, 0.5)]))
        status, code, _ = h.result(handle)
        assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.PATH_TOLERANCE_VIOLATED)
        wait_for(lambda: states, what='the unscaled controller state')
    finally:
        stop()
    assert set(states) == {1.0}
    h.cm.switch(activate=[SCALED], deactivate=[JTC])


def test_the_plain_controller_advances_by_its_own_speed_scaling_input(robot):
    """ros2_controllers' JTC (jazzy 4.39+): trajectory time advances by the controller's own factor, set through
    ~/speed_scaling_input (transient local): 2 runs twice as fast, 0 pauses; a negative factor is ignored with
    upstream's warning."""
    h = robot
    h.cm.switch(activate=[JTC], deactivate=[SCALED], strictness=BEST_EFFORT)
    core = h.sim._trajectory[JTC].core
    scaling = h.speed_scaling_input(JTC)
    log = h.rosout()
    try:
        scaling.publish(SpeedScalingFactor(factor=-1.0))
        wait_still(lambda: any(m == 'Scaling factor has to be greater or equal to 0.0 - Ignoring input!'
                               for n, m in log if n == JTC), what='the warning')
        assert core.speed_scaling == 1.0
        durations = {}
        for factor in (2.0, 0.5):
            scaling.publish(SpeedScalingFactor(factor=factor))
            t0 = h.sim.sim.time
            handle = _run(h, JTC, h.goal([point(h.q + 0.1, 1.0, ZERO)]))
            assert h.result(handle)[1] == rc.SUCCESSFUL
            durations[factor] = h.sim.sim.time - t0
        assert abs(durations[2.0] - 0.5) < 0.05 and abs(durations[0.5] - 2.0) < 0.05, durations
        scaling.publish(SpeedScalingFactor(factor=0.0))
        q0 = h.q
        handle = _run(h, JTC, h.goal([point(q0 + 0.2, 1.0, ZERO)]))
        h.wait_sim_time(1.5)
        assert np.abs(h.q - q0).max() < 1e-3  # paused
        scaling.publish(SpeedScalingFactor(factor=1.0))
        assert h.result(handle)[1] == rc.SUCCESSFUL
        assert np.abs(h.q - (q0 + 0.2)).max() < 0.02
    finally:
        scaling.publish(SpeedScalingFactor(factor=1.0))
        h.cm.switch(activate=[SCALED], deactivate=[JTC])


def test_the_scaled_controller_follows_the_robot_not_its_speed_scaling_input(robot):
    """a16a268's scaled controller has the inherited ~/speed_scaling_input, but its motion follows the hardware's
    factor; its controller_state reports the input (upstream's publish_state reports the base class's factor)."""
    h = robot
    h.cm.switch(activate=[SCALED], deactivate=[JTC], strictness=BEST_EFFORT)
    scaling = h.speed_scaling_input(SCALED)
    states: list[float] = []
    scaling.publish(SpeedScalingFactor(factor=0.0))  # would pause the plain controller
    stop = h.listen(JointTrajectoryControllerState, f'/{SCALED}/controller_state',  # every state after the input
                    lambda m: states.append(m.speed_scaling_factor), depth=10)
    try:
        q0 = h.q
        t0 = h.sim.sim.time
        handle = _run(h, SCALED, h.goal([point(q0 + 0.2, 1.0, ZERO)]))
        assert h.result(handle)[1] == rc.SUCCESSFUL
        assert h.sim.sim.time - t0 < 1.1
        assert np.abs(h.q - (q0 + 0.2)).max() < 0.02
        wait_for(lambda: states, what='the scaled controller state')
        assert set(states) == {0.0}
    finally:
        stop()
        scaling.publish(SpeedScalingFactor(factor=1.0))


def test_query_state(robot):
    h = robot
    h.cm.switch(activate=[SCALED], deactivate=[JTC], strictness=BEST_EFFORT)
    inactive = _query(h, JTC, 0.0)
    assert not inactive.success and 'not active' in inactive.message
    wait_for(lambda: h.sim.jtc.trajectory is None, what='no trajectory')
    assert not _query(h, SCALED, 0.0).success
    q0 = h.q
    target = q0 + np.array([0.4, 0, 0, 0, 0, 0])
    handle = _run(h, SCALED, h.goal([point(target, 4.0, ZERO)]))
    wait_for(lambda: h.sim.jtc.trajectory is not None, what='the trajectory')
    start = h.sim.jtc.trajectory.start_time
    answer = _query(h, SCALED, start + 4.0)
    assert answer.success and list(answer.name) == h.joints
    assert np.allclose(answer.position, target, atol=1e-9) and np.allclose(answer.velocity, 0.0, atol=1e-9)
    mid = _query(h, SCALED, start + 2.0)
    assert mid.success and abs(mid.position[0] - (q0[0] + 0.2)) < 0.01 and mid.velocity[0] > 0.1
    assert h.result(handle)[1] == rc.SUCCESSFUL


def test_controller_state_comes_every_control_cycle(robot):
    """ros2_controllers 4.39+ publishes controller_state from every update() (ur_controllers.yaml's
    state_publish_rate is no longer a JTC parameter); ur_sim sends it every cycle while someone subscribes."""
    h = robot
    h.cm.switch(activate=[SCALED], deactivate=[JTC], strictness=BEST_EFFORT)
    stamps: list[float] = []
    stop = h.listen(JointTrajectoryControllerState, f'/{SCALED}/controller_state',
                    lambda m: stamps.append(conv.time_to_sec(m.header.stamp)), depth=1000)
    try:
        wait_for(lambda: stamps, what='the first controller_state')
        t_end = h.sim.sim.time + 0.1
        h.wait_sim_time(0.1)
        wait_still(lambda: stamps[-1] >= t_end - 0.002 - 1e-9, what='the controller states of 0.1 s')
    finally:
        stop()
    periods = np.diff(np.array(stamps))
    assert len(periods) >= 50 and np.allclose(periods, h.sim.sim.control_dt, atol=1e-9), periods


def test_controller_state_is_filled_as_upstream_fills_it(robot):
    """reference: the trajectory in trajectory time (its velocities not scaled by the slider); error: positions only
    (no velocity error in a position-command configuration); output: the position command, the trajectory one update
    period later (command_next_), with no velocities or efforts (no such command interfaces)."""
    h = robot
    h.cm.switch(activate=[SCALED], deactivate=[JTC], strictness=BEST_EFFORT)
    slider = h.client.create_client(SetSpeedSliderFraction, '/io_and_status_controller/set_speed_slider')
    wait_still(slider.service_is_ready, what='set_speed_slider')
    assert wait_answer(slider.call_async(SetSpeedSliderFraction.Request(speed_slider_fraction=0.5))).success
    states: list[JointTrajectoryControllerState] = []
    stop = h.listen(JointTrajectoryControllerState, f'/{SCALED}/controller_state', states.append, depth=1000)
    try:
        wait_for(lambda: states, what='the first controller_state')
        q0 = h.q
        with following(lambda: conv.time_to_sec(states[-1].header.stamp)):  # every state of the move
            handle = _run(h, SCALED, h.goal([point(q0 + np.array([0.2, 0, 0, 0, 0, 0]), 2.0)]))  # linear
            assert h.result(handle)[1] == rc.SUCCESSFUL
    finally:
        stop()
    dt = h.sim.sim.control_dt
    moving = [m for m in list(states) if 0.01 < m.reference.positions[0] - q0[0] < 0.19]
    assert len(moving) > 1000  # 4 s at half speed
    for m in moving:
        assert m.reference.velocities[0] == pytest.approx(0.1, abs=1e-9)  # 0.2 rad in 2 s of trajectory time
        assert m.output.positions[0] - m.reference.positions[0] == pytest.approx(0.1 * dt, abs=1e-9)
        assert list(m.error.velocities) == [0.0] * 6 and len(m.feedback.velocities) == 6
        assert len(m.output.velocities) == 0 and len(m.output.effort) == 0
        assert m.error.positions[0] == pytest.approx(m.reference.positions[0] - m.feedback.positions[0], abs=1e-12)
        # reference.time_from_start is trajectory time: the linear move's position follows it exactly
        t_reference = conv.duration_to_sec(m.reference.time_from_start)
        assert m.reference.positions[0] - q0[0] == pytest.approx(0.1 * t_reference, abs=1e-6)
    # feedback.time_from_start is time since the start (one period a message), the reference's half of it (slider)
    t_feedback = np.array([conv.duration_to_sec(m.feedback.time_from_start) for m in moving])
    t_reference = np.array([conv.duration_to_sec(m.reference.time_from_start) for m in moving])
    assert np.allclose(np.diff(t_feedback), dt, atol=1e-9) and np.allclose(np.diff(t_reference), 0.5 * dt, atol=1e-9)
