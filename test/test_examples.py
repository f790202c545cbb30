"""Each seed 2 example script, run against an in-process ur_sim with the seed_ur10 preset."""
import sys
from pathlib import Path

import numpy as np
import pytest
from sim_harness import hand_over, running_sim

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'examples'))
import seed2_action_blocking  # noqa: E402
import seed2_action_monitor  # noqa: E402
import seed2_common as seed  # noqa: E402
import seed2_ik  # noqa: E402
import seed2_topic_p2p  # noqa: E402
import seed2_via_points  # noqa: E402

PRESET = dict(ur_type='ur10', namespace='/ur10', controller_name='vel_based_pos_traj_controller',
              initial_positions=[0.0] * 6, base_pose=[0.0, 0.0, 1.0, 0.0, 0.0, 0.0])


@pytest.fixture(scope='module')
def ur():
    # The examples stamp their trajectories 1 s of robot time ahead, wait on robot time and keep the client
    # library's wall-clock deadlines as guards. Paced, and with the client's messages handed over: a loaded machine
    # delayed a topic message by 3 s (DDS recovered a lost sample) while a free-running simulation moved on, and it
    # preempted the next example's goal. As fast as the client takes the robot's time (pace_speed 0; 3 x faster
    # than real time's pace on a quiet 2-core machine).
    with running_sim(paced=True, pace_speed=0.0, **PRESET) as h:
        client = seed.connect(context=h.client.context, node_name='example_client')
        try:
            h.pacer.follow(client.now)
            hand_over(h, client)
            yield client
        finally:
            client.close()


def test_ik_reproduces_the_seed_answer(ur, tmp_path):
    result = seed2_ik.run(ur, tmp_path)
    assert result['plots'][0].stat().st_size > 5_000
    assert result['max_difference'] < 1e-3
    # and the answer really is a solution: ee_link at the target in the seed's world
    kin = ur.kinematics('ee_link', seed.BASE_IN_WORLD)
    assert np.allclose(kin.fk(result['q']), seed.target_pose(), atol=1e-6)


def test_topic_point_to_point_with_50hz_recording(ur, tmp_path):
    result = seed2_topic_p2p.run(ur, tmp_path)
    rec = result['recording']
    assert len(rec.t) == 350  # the seed's N = (t_target + 0.5) x 50
    assert np.allclose(np.diff(rec.t), 1 / seed.RATE)
    assert result['final_error'] < 0.01
    assert all(p.is_file() and p.stat().st_size > 10_000 for p in result['plots'])


def test_task12_stops_and_task14_passes_through_the_via_point(ur, tmp_path):
    stop = seed2_via_points.run(ur, tmp_path, '12')
    through = seed2_via_points.run(ur, tmp_path, '14')
    # Task 12: every joint is at rest at the via point (the seed: q1 and q4 "come to a stop").
    assert np.abs(stop['velocity_at_via']).max() < 0.01
    # Task 14: joints 1 and 4 pass it with the commanded velocity; joint 1 never stops near it.
    assert through['velocity_at_via'][[0, 3]] == pytest.approx(seed.QVEL_TASK14[[0, 3]], abs=0.02)
    assert through['slowest_near_via'][0] > 0.2
    assert stop['final_error'] < 0.01 and through['final_error'] < 0.01


def test_blocking_action_succeeds_and_too_tight_tolerances_fail(ur, tmp_path):
    ok = seed2_action_blocking.run(ur, tmp_path, qtol=0.05)
    assert ok['outcome'].succeeded and all(p.is_file() for p in ok['plots'])
    outcome = seed2_action_blocking.run(ur, tmp_path, qtol=1e-7)['outcome']
    assert outcome.status == 'aborted'
    assert outcome.error_code in (-4, -5)  # a 1e-7 rad tube is left at once (path) or never reached (goal)


def test_non_blocking_action_with_monitoring(ur, tmp_path):
    result = seed2_action_monitor.run(ur, tmp_path)
    assert result['outcome'].succeeded
    assert len(result['feedback_errors']) > 50  # 6 s at 20 Hz
    assert max(result['feedback_errors']) < 0.01
    assert np.abs(result['recording'].q[-1] - seed.QF).max() < 0.01
