"""The seed's four figures of a plan, as images for the page."""
import numpy as np
import pytest

from ur_common.paths import config_dir
from ur_glue_planner.job import load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.studio.figures import FIGURES, bead_window, duration_text, plan_figures, speed_summary
from ur_glue_planner.studio.playback import Timeline


def test_four_non_blank_figures_and_the_speed_text():
    job = load_job(config_dir() / 'glue_job.yaml')
    plan = plan_job(job, np.array(job.home))
    images = plan_figures(plan)
    assert tuple(images) == FIGURES
    for name, image in images.items():
        assert image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8, name
        assert image.shape[0] > 200 and image.shape[1] > 500, name
        assert (image < 200).mean() > 0.01, f'{name} is blank'  # lines and text drawn on white
    text = speed_summary(plan)
    assert f'{plan.summary.speed_mean:.4f}' in text and 'Within 1 %' in text
    # What the user waited for, from the click, with the planner's share of it.
    waited = speed_summary(plan, 16.34)  # a loaded machine's wait: seconds, beside planning's share
    assert 'ready 16.3 s after Plan was pressed' in waited
    assert f'(planning {duration_text(plan.summary.planning_seconds)} of it)' in waited
    assert 'ready 734 ms after' in speed_summary(plan, 0.734)


def test_a_wait_in_the_unit_a_user_reads():
    assert duration_text(0.3604) == '360 ms' and duration_text(0.9994) == '999 ms'
    assert duration_text(1.0) == '1.0 s' and duration_text(41.26) == '41.3 s'


def test_the_figures_and_the_slider_say_which_time_they_show():
    job = load_job(config_dir() / 'glue_job.yaml')
    plan = plan_job(job, np.array(job.home))
    start, end = bead_window(plan)
    timeline = Timeline.from_plan(plan)
    bead_span = next((a, b) for name, a, b in timeline.spans if name == 'bead')
    assert (start, end) == pytest.approx(bead_span) and 0.0 < start < end < timeline.duration
    text = speed_summary(plan)
    assert f'0 to {plan.summary.total_duration:.2f} s' in text and f'{start:.2f} to {end:.2f} s' in text
