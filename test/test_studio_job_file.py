"""The studio's job file round trip: load -> teach -> save -> load gives the same job and the same plan."""
import dataclasses

import numpy as np
import pytest
import yaml

from ur_glue_planner.errors import JobError
from ur_glue_planner.job import default_job_path
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.studio.job_file import read_job, studio_job, teach_state, write_job


@pytest.fixture(scope='module')
def default():
    return read_job(None)


def test_loaded_job_becomes_saved_waypoints(default):
    state = teach_state(default.job)
    assert len(state.waypoints) == 22 and all(w.saved for w in state.waypoints)
    assert np.array_equal(state.planned_arrays()[0], np.array(default.job.path.waypoints))
    assert default.path == default_job_path()


def test_save_keeps_every_other_key_and_writes_the_planned_waypoints(default, tmp_path):
    state = teach_state(default.job).select(3).key('up').key('up').key('c').select(5).key('left')  # 5: unsaved
    written = write_job(tmp_path / 'taught.yaml', default, state)
    raw = yaml.safe_load((tmp_path / 'taught.yaml').read_text())
    original = yaml.safe_load(default_job_path().read_text())
    assert {k: v for k, v in raw.items() if k != 'path'} == {k: v for k, v in original.items() if k != 'path'}
    assert {k: v for k, v in raw['path'].items() if k not in ('waypoints', 'orientation_zyx')} == \
        {k: v for k, v in original['path'].items() if k not in ('waypoints', 'orientation_zyx')}
    assert len(raw['path']['waypoints']) == 21  # waypoint 6 was edited without C: skipped
    assert raw['path']['orientation_zyx'][3][2] == pytest.approx(-np.pi / 3 + 2 * np.radians(5.0), abs=1e-15)
    assert written.job == dataclasses.replace(studio_job(default, state).job, source_file=str(tmp_path / 'taught.yaml'))


def test_reloaded_file_plans_the_same_to_1e_9(default, tmp_path):
    state = teach_state(default.job).select(10).key('right').key('c').add([0.25, 0.82, 0.245]).key('c')
    in_memory = studio_job(default, state).job
    reloaded = write_job(tmp_path / 'job.yaml', default, state).job
    q0 = np.array(default.job.home)
    a, b = plan_job(in_memory, q0), plan_job(reloaded, q0)
    for sa, sb in zip(a.segments(), b.segments(), strict=True):
        assert sa.name == sb.name
        for x, y in ((sa.times, sb.times), (sa.q, sb.q), (sa.qd, sb.qd), (sa.qdd, sb.qdd)):
            assert x.shape == y.shape and np.abs(x - y).max() <= 1e-9


def test_fewer_than_two_planned_waypoints_is_an_error(default, tmp_path):
    state = teach_state(default.job)
    for _ in range(21):
        state = state.delete(0)
    with pytest.raises(JobError, match=r'path.waypoints: 1 waypoint\(s\) to plan; at least 2'):
        write_job(tmp_path / 'x.yaml', default, state)


def test_auto_job_is_taught_as_waypoints_on_the_glass(default, tmp_path):
    raw = yaml.safe_load(default_job_path().read_text())
    raw['path']['source'] = 'auto'
    raw['standoff'] = 0.004
    path = tmp_path / 'auto.yaml'
    path.write_text(yaml.safe_dump(raw))
    job = read_job(path)
    state = teach_state(job.job)
    from ur_glue_planner.scene.waypoints import job_waypoints, windshield_model
    points, _ = job_waypoints(job.job)
    assert len(state.waypoints) == len(points) > 50
    _, foot, _ = windshield_model(job.job.windshield).project(state.planned_arrays()[0])
    assert np.abs(foot - state.planned_arrays()[0]).max() < 1e-9  # on the glass (the stand-off is added again)
    saved = write_job(tmp_path / 'out.yaml', job, state).job
    points_back, rots_back = job_waypoints(saved)
    assert np.allclose(points_back, points, atol=1e-9)
    assert np.allclose(rots_back, job_waypoints(job.job)[1], atol=1e-12)
