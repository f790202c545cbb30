"""The seed's four figures of a plan, as images for the page."""
import numpy as np

from ur_glue_planner.job import load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.studio.figures import FIGURES, plan_figures, speed_summary
from ur_sim_driver.paths import config_dir


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
