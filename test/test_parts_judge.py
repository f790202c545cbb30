"""Judging glue runs on parts, summing them up, and the cell's refusals; pure."""
from __future__ import annotations

import re

import numpy as np
import pytest

from ur_glue_planner.parts.judge import MODES, meets_goal, refused, run_figures, summarize
from ur_glue_planner.scene.registration import CellLimits, Registration, refusal
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD


def bead(p95: float, mx: float, gaps: int, within: float) -> dict:
    return {'lateral_deviation_mm': {'mean': p95 / 2, 'p95': p95, 'max': mx}, 'gap_length_mm': 10.0 * gaps,
            'gaps': [{'station_mm': 100.0 * k, 'length_mm': 10.0} for k in range(gaps)],
            'width_within_band_fraction': within, 'closure': {'overlap_mm': 1.0}}


def part(index: int, corrected: dict, uncorrected: dict) -> dict:
    return {'index': index, 'part': {'offset_mm': [0, 0, 0]}, 'measured': None, 'corrected': corrected,
            'uncorrected': uncorrected}


def test_a_run_is_judged_by_its_bead() -> None:
    good = run_figures(bead(0.1, 0.2, 0, 0.98), 0, 'ok')
    assert good['lateral_p95_mm'] == 0.1 and good['gaps'] == 0 and meets_goal(good)
    assert not meets_goal(run_figures(bead(0.6, 0.7, 0, 0.98), 0))  # lateral p95 over 0.5 mm
    assert not meets_goal(run_figures(bead(0.1, 0.2, 1, 0.98), 0))  # a gap
    assert not meets_goal(run_figures(bead(0.1, 0.2, 0, 0.96), 0))  # width within 5 % on less than 97 %
    nothing = run_figures(None, -4, 'path tolerance')
    assert nothing['gaps'] == 1 and nothing['width_within_5pct'] == 0.0 and not meets_goal(nothing)
    assert not meets_goal(refused('too far off'))


def test_the_summary_holds_the_worst_accepted_part_and_counts_refusals() -> None:
    parts = [part(0, run_figures(bead(0.1, 0.2, 0, 0.98), 0), run_figures(bead(5.0, 6.0, 0, 0.9), 0)),
             part(1, run_figures(bead(0.3, 0.4, 0, 0.975), 0), run_figures(bead(7.0, 9.0, 2, 0.5), -1)),
             part(2, refused('turned 4 deg'), run_figures(bead(3.0, 4.0, 0, 0.97), 0))]
    s = summarize(parts)
    assert s['parts'] == 3 and set(MODES) <= set(s)
    c, u = s['corrected'], s['uncorrected']
    for mode in (c, u):
        assert {'lateral_p95_mm', 'lateral_max_mm', 'gaps', 'width_within_5pct', 'refused'} <= set(mode)
    assert (c['lateral_p95_mm'], c['lateral_max_mm'], c['gaps'], c['width_within_5pct']) == (0.3, 0.4, 0, 0.975)
    assert (c['refused'], c['accepted'], c['meeting_goal']) == (1, 2, 2)
    assert (u['lateral_p95_mm'], u['gaps'], u['refused'], u['meeting_goal']) == (7.0, 2, 0, 0)
    assert [r['index'] for r in c['per_part']] == [0, 1, 2]


def fit(offset_mm=(0.0, 0.0, 0.0), turn_deg=0.0, face_rms=5e-5, edge_max=1e-4, edges=8) -> Registration:
    t = np.eye(4)
    c, s = np.cos(np.radians(turn_deg)), np.sin(np.radians(turn_deg))
    t[:2, :2] = [[c, -s], [s, c]]
    centre = np.array([0.0, 0.6, 0.2])
    t[:3, 3] = centre + 1e-3 * np.array(offset_mm) - t[:3, :3] @ centre
    return Registration(t, centre, np.zeros(7), face_rms, 2 * face_rms, edge_max / 2, edge_max, 2400, edges,
                        DEFAULT_WINDSHIELD)


@pytest.mark.parametrize('found, reason', [
    (fit(), None),
    (fit(offset_mm=(0.0, 12.0, 0.0)), r'the part is \+12.0 mm off along y, beyond the 10 mm the cell corrects'),
    (fit(turn_deg=-3.5), r'the part is turned -3.50 deg about z, beyond the 3 deg the cell corrects'),
    (fit(edges=4), 'the scanners saw 4 glass edges, fewer than the 6 the fit needs'),
    (fit(face_rms=5e-4), r'the glass does not fit the known part: face residual 0.500 mm rms, limit 0.200 mm'),
    (fit(edge_max=8e-4), r'an edge is not where the fitted part has it: 0.800 mm off, limit 0.500 mm'),
])
def test_the_cell_refuses_what_it_cannot_correct_and_says_why(found: Registration, reason: str | None) -> None:
    said = refusal(found, CellLimits())
    assert (said is None) if reason is None else (said is not None and re.fullmatch(reason, said))
