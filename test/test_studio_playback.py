"""Playing a plan: the timeline over its segments, the playback clock, the bead coloured by speed."""
import numpy as np
import pytest

from ur_common.paths import config_dir
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.studio.playback import Clock, Timeline, bead_segments, speed_colors


@pytest.fixture(scope='module')
def plan():
    job = load_job(config_dir() / 'glue_job.yaml')
    return plan_job(job, np.array(job.home))


def test_timeline_joins_the_segments(plan):
    tl = Timeline.from_plan(plan)
    assert tl.duration == pytest.approx(plan.summary.total_duration, abs=1e-9)
    assert [s[0] for s in tl.spans] == ['approach', 'descent', 'bead', 'retreat']
    assert np.all(np.diff(tl.t) > 0)
    bead_start = tl.spans[2][1]
    assert np.allclose(tl.q_at(bead_start + plan.bead.times[100]), plan.bead.q[100], atol=1e-12)
    assert np.allclose(tl.q_at(0.0), plan.approach.q[0]) and np.allclose(tl.q_at(1e9), plan.retreat.q[-1])
    # tip positions are the forward kinematics of the joint positions
    k = len(tl.t) // 5
    assert np.allclose(tl.tip[k], plan.kinematics.fk(tl.q[k])[:3, 3], atol=1e-9)
    assert tl.segment_at(bead_start + 1.0) == 'bead'
    assert len(tl.tip_until(bead_start)) == int(np.searchsorted(tl.t, bead_start, side='right'))


def test_clock_plays_pauses_seeks_and_stops_at_the_end():
    c = Clock(10.0).with_speed(2.0)
    assert c.advance(1.0).t == 0.0  # paused
    c = c.play().advance(1.0)
    assert c.t == 2.0 and c.playing
    c = c.pause().advance(1.0)
    assert c.t == 2.0
    c = c.seek(9.5).play().advance(1.0)
    assert c.t == 10.0 and not c.playing
    assert c.play().t == 0.0  # play at the end starts over
    assert c.seek(-3.0).t == 0.0
    with pytest.raises(ValueError, match=r'playback speed 20 is not in \[0.05, 10\]'):
        c.with_speed(20)


def test_bead_colours_follow_the_planned_speed(plan):
    segs, colors = bead_segments(plan)
    assert segs.shape == (len(plan.bead.times) - 1, 2, 3) and colors.shape == segs.shape
    assert np.allclose(segs[:, 0], plan.bead.tip_pos[:-1])
    slow, fast = speed_colors(np.array([0.0, 0.15]), 0.15)
    assert not np.allclose(slow, fast)
    assert np.allclose(colors[0, 0], speed_colors(plan.bead.tcp_speed[:1], 1.1 * plan.job.tcp_speed)[0])
