"""One HTML page for the report: the video, the numbers (targets marked), and every figure, all relative links."""
from __future__ import annotations

import html
import json
from pathlib import Path

#: Bead targets on the default job (issue 13): (label, key path, test, text).
TARGETS = (
    ('width within +-5 % of nominal', ('width_within_band_fraction',), lambda v: v >= 0.97, '>= 97 % of the length'),
    ('gap length', ('gap_length_mm',), lambda v: v == 0.0, 'none'),
    ('closure overlap', ('closure', 'overlap_mm'), lambda v: v is not None and abs(v) <= 5.0, 'within +-5 mm'),
    ('lateral deviation (max)', ('lateral_deviation_mm', 'max'), lambda v: v <= 0.5, '<= 0.5 mm'),
)


def _get(d: dict, keys: tuple[str, ...]):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def _fmt(v) -> str:
    if isinstance(v, float):
        return f'{v:.4g}'
    return html.escape(str(v))


def targets_table(beads: dict[str, dict]) -> str:
    """Rows: the targets; columns: the methods (value, and pass/fail)."""
    head = ''.join(f'<th>{html.escape(m)}</th>' for m in beads)
    rows = []
    for label, keys, test, text in TARGETS:
        cells = []
        for figures in beads.values():
            v = _get(figures, keys)
            ok = v is not None and test(v)
            shown = f'{100 * v:.1f} %' if keys == ('width_within_band_fraction',) and v is not None else _fmt(v)
            cells.append(f'<td class="{"pass" if ok else "fail"}">{shown} {"&#10003;" if ok else "&#10007;"}</td>')
        rows.append(f'<tr><td>{html.escape(label)}</td><td>{html.escape(text)}</td>{"".join(cells)}</tr>')
    return f'<table><tr><th>figure</th><th>target</th>{head}</tr>{"".join(rows)}</table>'


def write_index(out_dir: Path, summary: dict, images: list[tuple[str, str]], video: str | None) -> Path:
    """Write out_dir/index.html.

    Args:
        summary: summary.json's content (shown in full at the end).
        images: (caption, file name relative to out_dir) in page order.
        video: MP4 file name relative to out_dir, or None.
    """
    out_dir = Path(out_dir)
    beads = {m: s['bead'] for m, s in (('ours', summary), ('seed 1', summary.get('baseline', {})))
             if isinstance(s, dict) and s.get('bead')}
    parts = ['<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>Glue job report</title>',
             '<style>body{font-family:sans-serif;max-width:1300px;margin:1em auto;padding:0 1em}'
             'img,video{max-width:100%;border:1px solid #ccc}table{border-collapse:collapse;margin:1em 0}'
             'td,th{border:1px solid #bbb;padding:3px 8px;text-align:left}.pass{background:#e3f6e3}'
             '.fail{background:#fbe3e3}pre{background:#f6f6f6;padding:1em;overflow:auto;font-size:12px}</style>',
             '</head><body>', '<h1>Glue job report</h1>',
             f'<p>Job <code>{html.escape(str(summary.get("job", "")))}</code>, '
             f'{html.escape(str(summary.get("ur_type")))}, result: '
             f'{html.escape(str(summary.get("result", {}).get("error_string") or "ok"))}</p>']
    if video:
        parts.append(f'<h2>The run</h2><video id="run-video" src="{html.escape(video)}" controls muted '
                     'preload="auto" width="640"></video>')
    if beads:
        parts.append('<h2>Bead targets</h2>' + targets_table(beads))
    disp = summary.get('dispenser')
    if disp:
        rows = ''.join(f'<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>' for k, v in disp.items()
                       if not isinstance(v, (list, dict)))
        parts.append(f'<h2>Dispenser switching</h2><table>{rows}</table>')
    parts.append('<h2>Figures</h2>')
    for caption, name in images:
        parts.append(f'<figure><img src="{html.escape(name)}" alt="{html.escape(caption)}">'
                     f'<figcaption>{html.escape(caption)}</figcaption></figure>')
    parts.append('<h2>summary.json</h2><pre>' + html.escape(json.dumps(summary, indent=2)) + '</pre>')
    parts.append('</body></html>')
    path = out_dir / 'index.html'
    path.write_text('\n'.join(parts))
    return path
