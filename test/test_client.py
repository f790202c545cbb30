"""The script client API against an in-process ur_sim (seed 2 preset names)."""
import time

import numpy as np
import pytest
from sim_harness import hand_over, running_sim, wait_for, wait_still

from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.client import DELIVERY_FACTOR, URClient
from ur_glue_planner.execution.joint_state_recording import STAMP_TIE

PRESET = dict(ur_type='ur10', namespace='/ur10', controller_name='vel_based_pos_traj_controller',
              initial_positions=[0.0] * 6, base_pose=[0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope='module')
def sim_and_client():
    # Paced, with its messages handed over and the client followed: a loaded machine's DDS delays (up to 3 s seen)
    # then change no stamp's margin and drop no joint state. As fast as the client takes the robot's time
    # (pace_speed 0): it waits on robot time and samples the joint states it has received; its wall-clock deadlines
    # only guard against a hang.
    with running_sim(paced=True, pace_speed=0.0, **PRESET) as h:
        client = URClient(namespace='/ur10', controller_name='vel_based_pos_traj_controller',
                          context=h.client.context, node_name='test_ur_client')
        try:
            h.pacer.follow(client.now)
            hand_over(h, client)
            yield h, client
        finally:
            client.close()


def test_server_not_found_names_the_action_and_timeout(sim_and_client):
    h, _ = sim_and_client
    with pytest.raises(ClientError, match=r'/nowhere/scaled_joint_trajectory_controller/follow_joint_trajectory '
                                          r'not found within 0.5 s'):
        URClient(namespace='/nowhere', timeout=0.5, context=h.client.context, node_name='lost_client')


def test_joint_state_and_blocking_move(sim_and_client):
    h, ur = sim_and_client
    state = ur.joint_state()
    assert state.names == tuple(h.joints) and state.q.shape == (6,)
    target = state.q + np.array([0.2, -0.1, 0.1, 0.0, 0.1, 0.0])
    outcome = ur.send_joint_configuration(target, end_time=1.0)
    assert outcome.succeeded, outcome
    assert np.abs(h.q - target).max() < 0.02


def test_non_blocking_goal_gives_feedback_and_cancels(sim_and_client):
    h, ur = sim_and_client
    q0 = ur.joint_state().q
    seen = []
    goal = ur.send_joint_configuration(q0 + np.array([0.8, 0, 0, 0, 0, 0]), end_time=4.0, wait=False,
                                       feedback_callback=seen.append)
    wait_for(lambda: len(seen) >= 3, what='feedback')
    assert goal.feedback is not None and len(goal.feedback.actual.positions) == 6
    goal.cancel()
    outcome = goal.wait(timeout=30)
    assert outcome.status == 'canceled'


def test_rejected_goal_raises_with_the_servers_reason(sim_and_client):
    _, ur = sim_and_client
    q = ur.joint_state().q.copy()
    q[2] = float('nan')
    with pytest.raises(ClientError, match=r'goal rejected by .*elbow_joint.* is not finite'):
        ur.send_joint_configuration(q, end_time=1.0)


def test_too_tight_goal_tolerance_gives_goal_tolerance_violated(sim_and_client):
    _, ur = sim_and_client
    q0 = ur.joint_state().q
    outcome = ur.follow_trajectory(q0[None, :] + 0.05, np.zeros((1, 6)), None, [0.5],
                                   goal_tolerance=ur.tolerances(1e-9), goal_time_tolerance=0.01)
    assert outcome.error_code == -5 and outcome.status == 'aborted'


def test_topic_and_recording(sim_and_client):
    h, ur = sim_and_client
    q0 = ur.joint_state().q
    ur.publish_trajectory([1.0], (q0 - 0.1)[None, :], np.zeros((1, 6)))
    # Stamp 0 starts the motion on arrival, which in fast mode can be a few tenths of a simulated second after
    # the publish; record from the moment the motion shows, so the window lies inside the 1 s move.
    wait_for(lambda: abs(ur.joint_state().q[0] - q0[0]) > 1e-4, what='the motion to start')
    rec = ur.record(duration=0.5, rate=50.0)
    assert rec.q.shape == (25, 6)  # N = duration x rate, as the seed counts
    assert np.allclose(np.diff(rec.t), 0.02)
    assert abs(rec.q[-1, 0] - rec.q[0, 0]) > 0.03  # it recorded the motion (about half of the 0.1 rad cubic)
    h.wait_sim_time(1.5)
    assert np.abs(ur.joint_state().q - (q0 - 0.1)).max() < 0.01


def test_a_listener_gets_every_joint_state_until_stopped(sim_and_client):
    h, ur = sim_and_client
    seen = []
    stop = ur.on_joint_state(seen.append)
    try:
        wait_for(lambda: len(seen) >= 20, what='20 joint states at the listener')
    finally:
        stop()
    count = len(seen)
    stamps = [s.t for s in seen]
    # Every message, in order, a control period apart (125 Hz on this CB3): none skipped, none twice.
    assert np.allclose(np.diff(stamps), h.sim.sim.control_dt, atol=1e-6), np.diff(stamps)
    assert seen[-1].names == ur.joint_names
    newest = ur.joint_state().t
    wait_for(lambda: ur.joint_state().t > newest, what='a newer joint state')
    assert len(seen) == count  # stopped


def test_the_public_import_path_gives_the_same_client():
    # Seed 2 scripts import the client from ur_glue_planner.client; the implementation lives in execution/.
    import ur_glue_planner.client as public
    from ur_glue_planner.execution import client as impl
    for name in public.__all__:
        assert getattr(public, name) is getattr(impl, name), name


def test_the_start_margin_grows_with_the_slowest_goal_answer(sim_and_client):
    _, ur = sim_and_client
    slow = 0.7  # [s] as if a loaded machine had answered a goal this late
    ur.goal_answers.append((slow, 1))
    try:
        now = ur.now()
        margin = ur.start_time(lead=0.1, delivery=0.3) - now
        # 0.1 s lead, then the larger of 0.3 s and DELIVERY_FACTOR x the slowest answer, scaled by time_rate() (at
        # least 1); the joint state that now() reads may be newer by the time start_time reads it again, not older
        assert margin >= 0.1 + DELIVERY_FACTOR * max(s for s, _ in ur.goal_answers) - STAMP_TIE  # on the system clock
    finally:
        ur.goal_answers.pop()


def test_a_built_goal_is_stamped_when_sent_and_its_answer_time_kept(sim_and_client):
    h, ur = sim_and_client
    q0 = ur.joint_state().q
    goal = ur.trajectory_goal(q0[None, :] + 0.05, np.zeros((1, 6)), None, [0.5])
    assert (goal.trajectory.header.stamp.sec, goal.trajectory.header.stamp.nanosec) == (0, 0)
    answered = len(ur.goal_answers)
    start = ur.start_time()
    before = time.monotonic()
    handle = ur.send_goal(goal, start_time=start, wait=False)
    within = time.monotonic() - before
    stamp = goal.trajectory.header.stamp
    assert stamp.sec + stamp.nanosec * 1e-9 == pytest.approx(start, abs=STAMP_TIE)
    assert len(ur.goal_answers) == answered + 1
    seconds, points = ur.goal_answers[-1]
    # The wall time from sending to the answer, taken within the call (not a bound on how long it may take).
    assert 0.0 < seconds <= within and points == 1
    assert handle.wait(timeout=30).succeeded


def test_the_spinning_thread_rests_only_while_nothing_runs_or_records(sim_and_client):
    from ur_glue_planner.execution.client import IDLE_PACE
    _, ur = sim_and_client
    assert ur._pace() == IDLE_PACE
    recorder = ur.start_recording()
    assert ur._pace() == 0.0  # every message counts while recording
    wait_for(lambda: recorder.samples, what='a recorded joint state')
    ur.stop_recording(recorder, raw=True)
    q0 = ur.joint_state().q
    goal = ur.send_joint_configuration(q0 + 0.02, end_time=1.0, wait=False)
    assert ur._pace() == 0.0 or goal.done  # feedback and the result are not held up
    assert goal.wait(timeout=30).succeeded
    assert ur._pace() == IDLE_PACE


def test_a_closed_client_leaves_the_graph(sim_and_client):
    h, _ = sim_and_client
    ur = URClient(namespace='/ur10', controller_name='vel_based_pos_traj_controller', context=h.client.context,
                  node_name='short_lived_client')
    try:
        wait_still(lambda: 'short_lived_client' in h.client.get_node_names(), what='the client in the graph')
    finally:
        ur.close()
    wait_still(lambda: 'short_lived_client' not in h.client.get_node_names(), what='the client gone from the graph')
