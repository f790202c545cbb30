"""Bead quality figures on synthetic beads: a perfect loop, a known gap, known blobs, a closure overlap and an
offset, against hand-computed values."""
from __future__ import annotations

import numpy as np
import pytest

from ur_glue_planner.report.bead_metrics import bead_quality, closure_overlap, project_onto_polyline
from ur_glue_planner.report.bead_report import write_bead_figure

W, H = 0.008, 0.0096  # nominal width and height [m]
SPEED, SPACING = 0.15, 0.0005  # [m/s], [m] between deposit points
CORNERS = np.array([[0.0, 0.0, 0.0], [0.4, 0.0, 0.0], [0.4, 0.2, 0.0], [0.0, 0.2, 0.0]])
LENGTH = 1.2


def loop_point(s: np.ndarray) -> np.ndarray:
    """Point at arc length s on the rectangle CORNERS (a loop of 1.2 m)."""
    s = np.mod(s, LENGTH)
    out = np.zeros((len(s), 3))
    for i, (a, b) in enumerate(zip(CORNERS, np.roll(CORNERS, -1, axis=0))):
        start = np.linalg.norm(np.diff(CORNERS[:i + 1], axis=0), axis=1).sum() if i else 0.0
        seg = np.linalg.norm(b - a)
        sel = (s >= start) & (s < start + seg)
        out[sel] = a + (s[sel] - start)[:, None] / seg * (b - a)
    return out


def bead(s_from: float = 0.0, s_to: float = LENGTH):
    s = np.arange(s_from, s_to + 1e-12, SPACING)
    return s, loop_point(s), np.full(len(s), W), np.full(len(s), H), s / SPEED


def quality(s, pts, w, h, t, **kw):
    return bead_quality(pts, w, h, t, CORNERS, W, closed=True, corner_stations=np.array([0.0, 0.4, 0.6, 1.0]),
                        **kw)[0]


def test_perfect_loop():
    fig = quality(*bead())
    assert fig['line_length_mm'] == pytest.approx(1200.0)
    assert fig['width_within_band_fraction'] == 1.0
    assert fig['gap_length_mm'] == 0.0 and fig['gaps'] == []
    assert fig['blobs'] == []
    assert fig['width_mm']['mean'] == pytest.approx(8.0, rel=1e-6)
    assert abs(fig['closure']['overlap_mm']) < 0.6
    assert fig['lateral_deviation_mm']['max'] < 1e-9


def test_known_gap_is_found_with_its_length():
    s, pts, w, h, t = bead()
    keep = (s < 0.300) | (s >= 0.320)
    fig = quality(s[keep], pts[keep], w[keep], h[keep], t[keep])
    assert fig['gap_length_mm'] == pytest.approx(20.0, abs=1.5)
    assert len(fig['gaps']) == 1 and fig['gaps'][0]['station_mm'] == pytest.approx(300.0, abs=1.5)
    assert fig['width_within_band_fraction'] == pytest.approx(1.0 - 0.02 / LENGTH, abs=0.0015)


def test_known_blob_on_the_line_and_one_at_the_start():
    s, pts, w, h, t = bead()
    blob = (s >= 0.200) & (s < 0.210)
    start = s < 0.005
    w, h = w.copy(), h.copy()
    w[blob], h[blob] = 1.5 * W, 1.5 * H
    w[start], h[start] = 2.0 * W, 2.0 * H
    fig = quality(s, pts, w, h, t)
    where = {b['where']: b for b in fig['blobs']}
    assert set(where) == {'line', 'start'}
    assert where['line']['station_mm'] == pytest.approx(205.0, abs=6.0)
    assert where['line']['length_mm'] == pytest.approx(10.0, abs=1.5)
    assert where['line']['peak_ratio'] == pytest.approx(1.5, rel=0.01)
    assert where['start']['peak_ratio'] == pytest.approx(2.0, rel=0.01)
    assert fig['width_mm']['max'] == pytest.approx(16.0, rel=0.01)
    assert fig['gap_length_mm'] == 0.0


def test_blob_at_a_corner_is_tagged_corner():
    s, pts, w, h, t = bead()
    near = np.abs(s - 0.4) < 0.003
    w, h = w.copy(), h.copy()
    w[near], h[near] = 1.3 * W, 1.3 * H
    assert [b['where'] for b in quality(s, pts, w, h, t)['blobs']] == ['corner']


def test_closure_overlap_and_its_double_layer():
    fig = quality(*bead(0.0, LENGTH + 0.004))
    assert fig['closure']['overlap_mm'] == pytest.approx(4.0, abs=0.6)
    # two passes on the same 4 mm add their sections: width sqrt(2) x nominal there
    [blob] = fig['blobs']
    assert blob['where'] == 'start' and blob['peak_ratio'] == pytest.approx(np.sqrt(2.0), rel=0.01)
    assert blob['length_mm'] == pytest.approx(4.0, abs=1.5)
    short = quality(*bead(0.0, LENGTH - 0.003))
    assert short['closure']['overlap_mm'] == pytest.approx(-3.0, abs=0.6)
    assert short['gap_length_mm'] == pytest.approx(3.0, abs=1.5)


def test_half_and_half_closure_counts_as_one_bead():
    # the start rises and the end falls over the same 10 mm so that their sections add to the nominal one
    s, pts, w, h, t = bead(0.0, LENGTH + 0.010)
    area = np.ones(len(s))
    area[s < 0.010] = s[s < 0.010] / 0.010
    area[s > LENGTH] = 1.0 - (s[s > LENGTH] - LENGTH) / 0.010
    area = area.clip(0.0, 1.0)
    w, h = W * np.sqrt(area), H * np.sqrt(area)
    fig = quality(s, pts, w, h, t)
    assert fig['width_within_band_fraction'] > 0.995 and fig['blobs'] == [] and fig['gap_length_mm'] == 0.0
    assert abs(fig['closure']['overlap_mm']) < 0.6  # both halves reach half width at the same station


def test_lateral_offset_and_standoff():
    s, pts, w, h, t = bead()
    shifted = pts + np.array([0.0, 0.0, 0.0003])
    fig = quality(s, shifted, w, h, t, standoff=np.full(len(s), 0.002))
    assert fig['lateral_deviation_mm']['mean'] == pytest.approx(0.3, abs=1e-6)
    assert fig['standoff_mm'] == pytest.approx({'mean': 2.0, 'min': 2.0, 'max': 2.0})


def test_no_material_is_all_gap():
    s, pts, w, h, t = bead()
    fig = quality(s, pts, np.zeros_like(w), h, t)
    assert fig['gap_length_mm'] == pytest.approx(1200.0) and fig['width_within_band_fraction'] == 0.0


def test_material_in_one_spot_only_is_no_bead_on_the_line():
    # The gun was on while the tip stood still (a run whose joint states or switching came too late): a blob,
    # but no length of bead. Reported as such, not as the statistics of an empty profile.
    s, pts, w, h, t = bead()
    spot = np.zeros_like(w)
    spot[10:20] = w[10:20]
    fig = quality(s, np.repeat(pts[10:11], len(pts), axis=0), spot, h, t)
    assert fig['deposit_points'] == 10 and 'width_mm' not in fig
    assert fig['gap_length_mm'] == pytest.approx(1200.0) and fig['width_within_band_fraction'] == 0.0


def test_no_bead_is_drawn_as_one_gap(tmp_path):
    # The report's figure of a run that laid no bead on the line: the whole line one gap, and the words.
    s, pts, w, h, t = bead()
    fig, prof = bead_quality(pts, np.zeros_like(w), h, t, CORNERS, W, closed=True)
    path = write_bead_figure([('ours', prof, fig)], tmp_path / 'bead.png')
    assert path.stat().st_size > 10_000 and fig['gaps'] == [{'station_mm': 0.0, 'length_mm': pytest.approx(1200.0)}]


def test_projection_and_closure_helpers():
    station, dist = project_onto_polyline(np.array([[0.1, 0.01, 0.0], [0.41, 0.1, 0.0]]), CORNERS)
    np.testing.assert_allclose(station, [0.1, 0.5])
    np.testing.assert_allclose(dist, [0.01, 0.01])
    assert closure_overlap(np.array([0.0, 0.5]), np.zeros(2), W, LENGTH)['overlap_mm'] is None
