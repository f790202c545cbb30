"""The report's video and HTML page: an H.264 MP4 of a short run with the bead growing, and the page in headless
Chromium (it loads, the video has a duration, no image is broken)."""
from __future__ import annotations

import json

import imageio_ffmpeg
import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from studio_browser import launched_chromium  # noqa: E402

from ur_glue_planner.execution.bead_listener import BeadPoints  # noqa: E402
from ur_glue_planner.report.bead_metrics import bead_quality  # noqa: E402
from ur_glue_planner.report.html_page import write_index  # noqa: E402
from ur_glue_planner.report.video import render_video  # noqa: E402
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD  # noqa: E402
from ur_sim_driver.description.params import load_ur_params  # noqa: E402
from ur_sim_driver.description.scene import config_dir, pose_matrix  # noqa: E402
from ur_sim_driver.description.tool import get_tool  # noqa: E402

HOME = np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0])


@pytest.fixture(scope='module')
def report_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp('report')
    t = np.linspace(0.0, 1.0, 51)
    q = HOME + np.outer(t, [0.5, 0.2, -0.3, 0.0, 0.4, 0.0])
    s = np.linspace(0.0, 0.15, 151)
    # along the glass's lower edge, on the glass (seed 1's first clicks lie there)
    pts = DEFAULT_WINDSHIELD.project(np.column_stack([-0.2 + s, np.full_like(s, 0.418), np.full_like(s, 0.145)]))[1]
    bead = BeadPoints(pts, np.full(len(s), 0.008), np.full(len(s), 0.0096), 100.0 + s / 0.15)
    mesh = config_dir().parent / 'meshes' / 'windshield.stl'
    frames = []
    scene = [('windshield', mesh, pose_matrix((0, 0.4, 0.15), (-0.9599, 0, 0)))]
    arm, tool = load_ur_params('ur5'), get_tool('dispenser')
    info = render_video(arm, tool, scene, t, q, out / 'run.mp4', bead=bead, bead_t0=100.0, width=320, height=240,
                        progress=lambda done, total, _: frames.append((done, total)))
    fig, ax = plt.subplots()
    ax.plot(s, s)
    fig.savefig(out / 'figure.png')
    plt.close(fig)
    figures = bead_quality(pts, bead.widths, bead.heights, bead.times, pts, 0.008, closed=False)[0]
    summary = {'job': 'test', 'ur_type': 'ur5', 'result': {'error_code': 0, 'error_string': ''}, 'bead': figures,
               'dispenser': {'pin': 16, 't_on': 0.3}}
    (out / 'summary.json').write_text(json.dumps(summary))
    write_index(out, summary, [('a figure', 'figure.png')], 'run.mp4')
    return out, info, frames, scene, t, q


def test_video_is_h264_at_30_fps_with_every_frame(report_dir):
    out, info, progress, scene, t, q = report_dir
    assert info['frames'] == 31 and info['fps'] == 30
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(out / 'run.mp4'))
    assert frames == 31 and seconds == pytest.approx(31 / 30, abs=0.05)
    reader = imageio_ffmpeg.read_frames(str(out / 'run.mp4'))
    meta = next(reader)
    assert meta['codec'].startswith('h264') and tuple(meta['size']) == (320, 240)
    with_bead = [np.frombuffer(f, np.uint8).reshape(240, 320, 3).astype(int) for f in reader]
    assert np.abs(with_bead[0] - with_bead[-1]).mean() > 0.2  # the arm moved
    # the same run without the bead: the frames differ only where the bead has grown
    render_video(load_ur_params('ur5'), get_tool('dispenser'), scene, t, q, out / 'no_bead.mp4', width=320,
                 height=240, progress=None)
    reader = imageio_ffmpeg.read_frames(str(out / 'no_bead.mp4'))
    next(reader)
    without = [np.frombuffer(f, np.uint8).reshape(240, 320, 3).astype(int) for f in reader]
    changed = [int((np.abs(a - b).max(axis=2) > 30).sum()) for a, b in zip(with_bead, without)]
    assert changed[0] == 0 and changed[15] >= 8 and changed[-1] >= changed[15] + 8  # ~1 pixel per 5 mm of bead
    assert progress[-1] == (31, 31)


def test_page_loads_with_a_playable_video_and_no_broken_image(report_dir):
    out = report_dir[0]
    with launched_chromium() as browser:
        page = browser.new_page()
        page.goto((out / 'index.html').as_uri())
        page.wait_for_function("document.querySelector('#run-video').readyState >= 1", timeout=30_000)
        duration = page.evaluate("document.querySelector('#run-video').duration")
        assert duration == pytest.approx(31 / 30, abs=0.05)
        page.wait_for_function("[...document.images].every(i => i.complete)", timeout=30_000)
        broken = page.evaluate("[...document.images].filter(i => i.naturalWidth === 0).map(i => i.src)")
        assert page.evaluate("document.images.length") == 1 and broken == []
        assert 'Bead targets' in page.content()
