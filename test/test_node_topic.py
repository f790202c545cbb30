"""JointTrajectory topic, interpolation order, speed scaling and partial goals on a running ur_sim."""
import numpy as np
from action_msgs.msg import GoalStatus
from sim_harness import point, running_sim, trajectory, wait_answer, wait_still
from ur_msgs.srv import SetSpeedSliderFraction

from ur_sim_driver.motion import result_codes as rc

ZERO = np.zeros(6)


def _first_motion_time(t, q, q0, threshold=1e-3):
    moved = np.flatnonzero(np.abs(q - q0).max(axis=1) > threshold)
    return t[moved[0]]


def _settle_time(t, q, target, threshold=2e-3):
    far = np.flatnonzero(np.abs(q - target).max(axis=1) > threshold)
    assert far.size and far[-1] + 1 < len(t), 'the recording ended before the robot settled at the target'
    return t[far[-1] + 1]


def test_topic_moves_and_replaces_active_trajectory():
    with running_sim() as h:
        q0 = h.q
        h.topic.publish(trajectory(h.joints, [point(q0 + 0.5, 4.0, ZERO)]))
        h.wait_sim_time(0.5)
        replacement = q0 - np.array([0.2, 0, 0, 0, 0, 0])
        h.topic.publish(trajectory(h.joints, [point(replacement, 1.0, ZERO)]))
        h.wait_sim_time(2.0)
        assert np.abs(h.q - replacement).max() < 0.005
        # An invalid message is dropped and the robot keeps holding.
        h.topic.publish(trajectory(h.joints, [point(q0 + np.array([0, 0, np.nan, 0, 0, 0]), 1.0)]))
        h.wait_sim_time(1.0)
        assert np.abs(h.q - replacement).max() < 0.005


def test_topic_preempts_an_action_goal():
    with running_sim() as h:
        handle = h.send(h.goal([point(h.q + 0.3, 3.0, ZERO)]))
        h.wait_sim_time(0.2)
        h.topic.publish(trajectory(h.joints, [point(h.q, 0.5, ZERO)]))
        status, code, text = h.result(handle)
        assert (status, code) == (GoalStatus.STATUS_ABORTED, rc.INVALID_GOAL)
        assert 'preempted' in text


def test_cubic_and_quintic_are_told_apart_in_joint_states():
    """Cubic (velocities given) starts with a jump in acceleration; quintic (accelerations too) does not."""
    early_speed = {}
    with running_sim() as h:
        for kind in ('cubic', 'quintic'):
            # The previous goal ends within its goal tolerance, not at rest: the arm still creeps by more than the
            # 1e-6 rad threshold below, which would read as this goal's motion before it was sent.
            h.wait_sim_time(1.0)
            h.record()
            q0 = h.q
            target = q0 + np.array([0.6, 0, 0, 0, 0, 0])
            acc = ZERO if kind == 'quintic' else None
            t_send = h.sim.sim.time
            handle = h.send(h.goal([point(target, 2.0, ZERO, acc)]))
            assert h.result(handle)[1] == rc.SUCCESSFUL
            t, q, qd = h.stop_recording().arrays()
            t0 = _first_motion_time(t, q, q0, 1e-6)
            sel = (t > t0 + 0.08) & (t < t0 + 0.12)
            # Latency is a benchmark figure (in fast mode a slow DDS hop is much simulated time, so no bound on
            # when the motion starts): only the shape counts here, and the motion must be this goal's.
            assert sel.any() and t0 - t_send > -0.01  # stamps are cycle starts: a cycle early is fine
            early_speed[kind] = np.mean(qd[sel, 0])
    # Cubic through 0.6 rad in 2 s: qd(0.1 s) ~ 6*0.6*(0.05 - 0.0025)/2 = 0.0855 rad/s; quintic ~ 0.0205 rad/s.
    assert 0.06 < early_speed['cubic'] < 0.11
    assert 0.01 < early_speed['quintic'] < 0.03


def test_speed_slider_at_half_doubles_the_scaled_controllers_execution_time():
    """The scaled controller advances trajectory time by the robot's speed scaling, which the slider multiplies
    (the robot keeper puts the slider back after the test)."""
    durations = {}
    with running_sim() as h:
        slider = h.client.create_client(SetSpeedSliderFraction, '/io_and_status_controller/set_speed_slider')
        wait_still(slider.service_is_ready, what='set_speed_slider')
        for fraction in (1.0, 0.5):
            request = SetSpeedSliderFraction.Request(speed_slider_fraction=fraction)
            assert wait_answer(slider.call_async(request)).success
            q0 = h.q
            target = q0 + np.array([0.3, -0.2, 0.2, 0, 0, 0])
            h.record()
            handle = h.send(h.goal([point(target, 1.0, ZERO)]))
            assert h.result(handle)[1] == rc.SUCCESSFUL
            h.wait_sim_time(0.3)  # the goal succeeds within the goal tolerance; record the settling too
            t, q, _ = h.stop_recording().arrays()
            durations[fraction] = _settle_time(t, q, target) - _first_motion_time(t, q, q0)
    assert abs(durations[0.5] / durations[1.0] - 2.0) < 0.05


def test_partial_goal_in_any_order_is_mapped_by_name():
    with running_sim(allow_partial_joints_goal=True) as h:
        q0 = h.q
        names = ['wrist_2_joint', 'shoulder_pan_joint']
        handle = h.send(h.goal([point([0.4, -0.3], 1.0, [0.0, 0.0])], names=names))
        assert h.result(handle)[1] == rc.SUCCESSFUL
        expected = q0.copy()
        expected[4], expected[0] = 0.4, -0.3
        assert np.abs(h.q - expected).max() < 0.005
