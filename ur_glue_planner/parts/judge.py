"""One glue run on one part judged, and the runs over all parts summed up; pure (numpy only).

A run is judged by the bead figures of ``report/bead_metrics.py`` against the line where the bead belongs on the
part as it really is (the nominal line carried onto the part's glass), whatever the planner believed:

- ``lateral_p95_mm``, ``lateral_max_mm``: the bead centre's distance to that line, 95th percentile and largest;
- ``gaps``: how many stretches of the line got no material (``gap_length_mm``: their length);
- ``width_within_5pct``: the share of the line's length where the bead is within +-5 % of its nominal width;
- ``refused``: the reason the cell refused the part (nothing dispensed; no figures), else None.
"""
from __future__ import annotations

import numpy as np

METRICS = ('lateral_p95_mm', 'lateral_max_mm', 'gaps', 'width_within_5pct')
MODES = ('corrected', 'uncorrected')
#: The goal on every accepted part with correction (#26): the figure and its bound.
GOAL = {'lateral_p95_mm': ('<=', 0.5), 'gaps': ('<=', 0), 'width_within_5pct': ('>=', 0.97)}


def run_figures(bead: dict | None, error_code: int | None, error_string: str = '') -> dict:
    """The judged figures of one run from its bead figures (``analyse_bead``'s dict; None: no bead at all)."""
    result = {'refused': None, 'error_code': error_code, 'error_string': error_string}
    if not bead or 'lateral_deviation_mm' not in bead:
        length = bead.get('line_length_mm', 0.0) if bead else 0.0
        return {**result, 'lateral_p95_mm': None, 'lateral_max_mm': None, 'gaps': 1,
                'gap_length_mm': length, 'width_within_5pct': 0.0}
    lateral = bead['lateral_deviation_mm']
    return {**result, 'lateral_p95_mm': lateral['p95'], 'lateral_max_mm': lateral['max'],
            'gaps': len(bead['gaps']), 'gap_length_mm': bead['gap_length_mm'], 'gaps_at_mm': bead['gaps'],
            'closure_overlap_mm': bead.get('closure', {}).get('overlap_mm'),
            'width_within_5pct': bead['width_within_band_fraction']}


def refused(reason: str) -> dict:
    """A run the cell refused: no figures."""
    return {'refused': reason, 'error_code': None, 'error_string': '', **{m: None for m in METRICS},
            'gap_length_mm': None}


def meets_goal(figures: dict) -> bool:
    """Whether an accepted run meets the goal (GOAL); a refused run does not count either way (False)."""
    if figures['refused'] is not None or figures['lateral_p95_mm'] is None:
        return False
    return all((figures[k] <= bound) if op == '<=' else (figures[k] >= bound) for k, (op, bound) in GOAL.items())


def _worst(runs: list[dict], key: str, pick) -> float | None:
    values = [r[key] for r in runs]
    return float(pick(values)) if values else None


def summarize(parts: list[dict]) -> dict:
    """summary.json: ``parts`` (how many), and per mode the worst figure over the accepted parts, how many parts
    were refused, how many met the goal, and every part's figures.

    Args:
        parts: one dict per part: ``index``, ``part`` (what was generated), ``measured`` (what the fit found, or
            None) and one judged figures dict per mode.
    """
    out: dict = {'parts': len(parts)}
    for mode in MODES:
        runs = [p[mode] for p in parts if mode in p]
        accepted = [r for r in runs if r['refused'] is None and r['lateral_p95_mm'] is not None]

        out[mode] = {
            'lateral_p95_mm': _worst(accepted, 'lateral_p95_mm', np.max),
            'lateral_max_mm': _worst(accepted, 'lateral_max_mm', np.max),
            'gaps': int(sum(r['gaps'] for r in runs if r['refused'] is None)),
            'width_within_5pct': _worst(accepted, 'width_within_5pct', np.min),
            'refused': sum(r['refused'] is not None for r in runs),
            'accepted': len(accepted),
            'meeting_goal': sum(meets_goal(r) for r in runs),
            'per_part': [{'index': p['index'], **p[mode]} for p in parts if mode in p],
        }
    out['goal'] = {k: f'{op} {bound}' for k, (op, bound) in GOAL.items()}
    out['generated'] = [{'index': p['index'], **p['part'], 'measured': p.get('measured')} for p in parts]
    return out
