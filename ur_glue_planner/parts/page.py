"""``index.html`` of a parts run: the figures over the parts, one plot each, corrected beside uncorrected.

Each plot shows one figure of ``judge.METRICS`` against the part's index: corrected runs as dots, uncorrected as
crosses, the goal's bound as a dashed line, refused parts as a grey band (nothing dispensed).
"""
from __future__ import annotations

import html
import json
from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, NullFormatter  # noqa: E402

from ur_glue_planner.parts.judge import GOAL, METRICS, MODES  # noqa: E402

LABELS = {'lateral_p95_mm': 'bead centre to line, 95th percentile [mm]', 'lateral_max_mm':
          'bead centre to line, largest [mm]', 'gaps': 'gaps in the bead [count]',
          'width_within_5pct': 'share of the length within +-5 % of the width'}
STYLE = {'corrected': dict(marker='o', ls='', color='tab:green'), 'uncorrected': dict(marker='x', ls='',
                                                                                      color='tab:red')}


def plot_metric(summary: dict, metric: str, path: Path) -> Path:
    """One figure over the parts as a PNG."""
    fig, ax = plt.subplots(figsize=(8, 3.2), constrained_layout=True)
    for mode in MODES:
        runs = summary[mode]['per_part']
        xs = [r['index'] for r in runs if r.get(metric) is not None]
        ys = [r[metric] for r in runs if r.get(metric) is not None]
        ax.plot(xs, ys, label=mode, **STYLE[mode])
        for r in runs:
            if r['refused'] is not None and mode == 'corrected':
                ax.axvspan(r['index'] - 0.4, r['index'] + 0.4, color='0.85', lw=0)
    if metric in GOAL:
        ax.axhline(GOAL[metric][1], color='k', ls='--', lw=0.8, label=f'goal {GOAL[metric][0]} {GOAL[metric][1]}')
    if metric.startswith('lateral'):  # corrected tenths of a millimetre, uncorrected millimetres: both readable
        ax.set_yscale('log')
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f'{v:g}'))
        ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set(xlabel='part', ylabel=LABELS[metric].split(',')[0] if len(LABELS[metric]) > 40 else LABELS[metric],
           title=LABELS[metric])
    ax.grid(True, alpha=0.4)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path


def _row(mode: str, s: dict) -> str:
    def f(x, fmt):
        return '-' if x is None else format(x, fmt)
    return (f"<tr><td>{mode}</td><td>{f(s['lateral_p95_mm'], '.3f')}</td><td>{f(s['lateral_max_mm'], '.3f')}</td>"
            f"<td>{s['gaps']}</td><td>{f(s['width_within_5pct'], '.3f')}</td><td>{s['refused']}</td>"
            f"<td>{s['meeting_goal']} of {s['accepted']}</td></tr>")


def write_page(out_dir: Path, summary: dict) -> Path:
    """Write the plots and ``index.html`` into ``out_dir``; returns the page's path."""
    images = [plot_metric(summary, m, out_dir / f'{m}.png').name for m in METRICS]
    refusals = [f"<li>part {r['index']}: {html.escape(r['refused'])}</li>" for r in summary['corrected']['per_part']
                if r['refused'] is not None]
    page = f"""<!doctype html><html><head><meta charset="utf-8"><title>Glue on {summary['parts']} parts</title>
<style>body{{font-family:sans-serif;max-width:60em;margin:1em auto}}td,th{{padding:2px 8px;text-align:right}}</style>
</head><body><h1>Glue on {summary['parts']} generated windshields (seed {summary.get('seed')})</h1>
<p>Each part placed off by up to {json.dumps(summary.get('limits'))} (placement [m], rotation [deg], shape [m]),
run twice on a fresh ur_sim: <b>corrected</b> (measured by the cell's scanners, the bead moved onto the measured
glass) and <b>uncorrected</b> (the bead planned on the nominal glass). Worst over the accepted parts:</p>
<table><tr><th></th><th>lateral p95 [mm]</th><th>lateral max [mm]</th><th>gaps</th><th>width within 5 %</th>
<th>refused</th><th>meeting the goal</th></tr>{''.join(_row(m, summary[m]) for m in MODES)}</table>
<p>Goal with correction, on every accepted part: {html.escape(json.dumps(summary['goal']))}.</p>
{'<h2>Refused</h2><ul>' + ''.join(refusals) + '</ul>' if refusals else ''}
{''.join(f'<p><img src="{name}" alt="{name}"></p>' for name in images)}
<p>Numbers: <a href="summary.json">summary.json</a>; each part's scene, ur_sim log and figures in part_NNN/.</p>
</body></html>
"""
    path = out_dir / 'index.html'
    path.write_text(page)
    return path
