"""Quality figures of a deposited glue bead against its intended centre line, pure (numpy only).

The bead comes as deposit points in time order (centre (N, 3) [m], width, height [m], time [s]), as ur_sim
publishes it on /ur_sim/glue_bead or a measuring system would deliver it. Every point is placed on the intended
line by its nearest point there: its *station* (arc length along the line [m]) and its *lateral deviation*
(distance to the line [m]). Consecutive points (one pass of the nozzle) cover the stations between them; where
two passes cover the same station (the closure of a loop) their cross-sections add. The bead's width at a
station is the width of that summed cross-section at the bead's own shape (the median height / width ratio of
its points), so a single pass keeps its own width, and a closure that lays half and half counts as one bead.

Figures, each over the intended line sampled every ``step`` [m]:
- width: mean, min, max and the share of the line's length within +-``band`` of the nominal width,
- gaps: stations without material (total length, and each gap's start and length),
- blobs: runs wider than nominal + band, each tagged 'start', 'stop', 'corner' or 'line' by where it lies,
- closure (loops): where the bead reaches half its nominal section at the start and at the end, and the
  overlap between them [m] (> 0: the end runs past the start; < 0: it stops short),
- lateral deviation of the bead centre from the line, and the standoff when given.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class StationProfile:
    """The bead along the intended line.

    Attributes:
        station: (S,) [m] arc length along the line. width: (S,) [m], 0 where no material.
        passes: (S,) how many passes of the nozzle laid material there.
        point_station, point_lateral: (N,) [m] of each deposit point with material (empty if not computed).
    """

    station: np.ndarray
    width: np.ndarray
    passes: np.ndarray
    point_station: np.ndarray = field(default_factory=lambda: np.empty(0))
    point_lateral: np.ndarray = field(default_factory=lambda: np.empty(0))


def project_onto_polyline(points: np.ndarray, line: np.ndarray, chunk: int = 512) -> tuple[np.ndarray, np.ndarray]:
    """Station [m] (N,) and distance [m] (N,) of each point (N, 3) on the polyline line (P, 3)."""
    a, b = line[:-1], line[1:]
    ab = b - a
    seg_len = np.linalg.norm(ab, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    ab2 = np.maximum(seg_len ** 2, 1e-30)
    station, dist = np.empty(len(points)), np.empty(len(points))
    for i in range(0, len(points), chunk):
        p = points[i:i + chunk, None, :]
        t = np.clip(((p - a) * ab).sum(axis=2) / ab2, 0.0, 1.0)
        d = np.linalg.norm(p - (a + t[..., None] * ab), axis=2)
        k = np.argmin(d, axis=1)
        rows = np.arange(len(k))
        station[i:i + chunk] = cum[k] + t[rows, k] * seg_len[k]
        dist[i:i + chunk] = d[rows, k]
    return station, dist


def split_passes(station: np.ndarray, times: np.ndarray, max_jump: float, max_pause: float) -> list[np.ndarray]:
    """Index runs of consecutive deposit points that form one continuous pass (no jump in station larger
    than ``max_jump`` [m], no pause in time longer than ``max_pause`` [s])."""
    if len(station) == 0:
        return []
    cut = (np.abs(np.diff(station)) > max_jump) | (np.diff(times) > max_pause)
    return np.split(np.arange(len(station)), np.flatnonzero(cut) + 1)


def station_profile(station: np.ndarray, widths: np.ndarray, heights: np.ndarray, times: np.ndarray,
                    length: float, closed: bool, step: float = 0.001, max_jump: float = 0.01,
                    max_pause: float = 0.2) -> StationProfile:
    """Width of the bead at stations 0, step, ... < length (loops) or <= length (open lines).

    Args:
        station, widths, heights, times: (N,) per deposit point, time order ([m], [m], [m], [s]).
        length: Length of the intended line [m]. closed: The line is a loop (stations wrap).
        step: Station spacing [m]. max_jump, max_pause: See :func:`split_passes`.
    """
    grid = np.arange(0.0, length - (0.5 * step if closed else -0.5 * step), step)
    area = np.zeros(len(grid))
    passes = np.zeros(len(grid), dtype=int)
    keep = widths > 0.0
    st, w, h, t = station[keep], widths[keep], heights[keep], times[keep]
    if closed and len(st):
        st = np.unwrap(st, period=length)  # a pass over the loop's start continues beyond `length`
    ratio = float(np.median(h / w)) if len(w) else 1.0
    for run in split_passes(st, t, max_jump, max_pause):
        s_run, a_run = st[run], w[run] * h[run]
        order = np.argsort(s_run)
        s_run, a_run = s_run[order], a_run[order]
        lo, hi = s_run[0], s_run[-1]
        if hi - lo < 1e-12:
            continue
        shifts = (length * np.arange(np.floor(lo / length) - 1, np.ceil(hi / length) + 1) if closed else (0.0,))
        for shift in shifts:
            g = grid + shift
            inside = (g >= lo) & (g < hi)  # half-open: a loop closing exactly on its start counts once
            area[inside] += np.interp(g[inside], s_run, a_run)
            passes[inside] += 1
    width = np.sqrt(np.maximum(area, 0.0) / ratio)
    return StationProfile(grid, width, passes)


def _runs(flag: np.ndarray) -> list[tuple[int, int]]:
    idx = np.flatnonzero(flag)
    if idx.size == 0:
        return []
    parts = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    return [(int(p[0]), int(p[-1])) for p in parts]


def _near(x: float, targets: np.ndarray, radius: float, length: float, closed: bool) -> bool:
    if len(targets) == 0:
        return False
    d = np.abs(np.asarray(targets) - x)
    if closed:
        d = np.minimum(d, length - d)
    return bool(d.min() <= radius)


def bead_quality(points: np.ndarray, widths: np.ndarray, heights: np.ndarray, times: np.ndarray,
                 line: np.ndarray, nominal_width: float, closed: bool, corner_stations: np.ndarray = (),
                 standoff: np.ndarray | None = None, band: float = 0.05, step: float = 0.001,
                 near: float = 0.03) -> tuple[dict, StationProfile]:
    """Every figure of the bead against its line (see the module text); lengths in the dict are in mm.

    Args:
        points (N, 3) [m], widths, heights (N,) [m], times (N,) [s]: the deposit points in time order.
        line: (P, 3) [m] the intended centre line on the glass (a loop's last point may repeat the first).
        nominal_width: [m]. closed: The bead is a loop.
        corner_stations: Stations [m] of the line's corners (blobs there are tagged 'corner').
        standoff: (N,) [m] nozzle tip to glass at each deposit point, or None.
        band: Relative width tolerance. step: Station spacing [m]. near: Radius [m] of 'start'/'stop'/'corner'.

    Returns:
        (figures for summary.json, the station profile for plotting).
    """
    points, widths = np.asarray(points, dtype=float), np.asarray(widths, dtype=float)
    heights, times = np.asarray(heights, dtype=float), np.asarray(times, dtype=float)
    line = np.asarray(line, dtype=float)
    length = float(np.linalg.norm(np.diff(line, axis=0), axis=1).sum())
    if closed and np.linalg.norm(line[-1] - line[0]) > 1e-9:
        length += float(np.linalg.norm(line[-1] - line[0]))
        line = np.vstack([line, line[:1]])
    wet = widths > 0.0

    def no_bead() -> tuple[dict, StationProfile]:  # nothing deposited, or nothing of it on the line
        empty = StationProfile(np.arange(0.0, length, step), np.zeros(int(np.ceil(length / step))),
                               np.zeros(int(np.ceil(length / step)), dtype=int))
        return {'deposit_points': int(wet.sum()), 'line_length_mm': 1e3 * length, 'gap_length_mm': 1e3 * length,
                'gaps': [{'station_mm': 0.0, 'length_mm': 1e3 * length}], 'blobs': [], 'band': band,
                'width_within_band_fraction': 0.0, 'nominal_width_mm': 1e3 * nominal_width}, empty

    if not np.any(wet):
        return no_bead()
    station, lateral = project_onto_polyline(points, line)
    prof = station_profile(station, widths, heights, times, length, closed, step)
    w, ok = prof.width, np.abs(prof.width - nominal_width) <= band * nominal_width
    covered = prof.width > 0.0
    if not np.any(covered):
        return no_bead()
    first, last = np.flatnonzero(wet)[[0, -1]]
    s_first, s_last = float(station[first]), float(station[last])
    gaps = [(float(prof.station[a]), (b - a + 1) * step) for a, b in _runs(~covered)]
    blobs = []
    for a, b in _runs(w > (1.0 + band) * nominal_width):
        k = a + int(np.argmax(w[a:b + 1]))
        x = float(prof.station[k])
        where = ('start' if _near(x, [s_first], near, length, closed) else
                 'stop' if _near(x, [s_last], near, length, closed) else
                 'corner' if _near(x, np.asarray(corner_stations, dtype=float), near, length, closed) else 'line')
        excess = float(((w[a:b + 1] ** 2 - nominal_width ** 2).clip(min=0.0)).sum() * step)
        blobs.append({'station_mm': 1e3 * x, 'length_mm': 1e3 * (b - a + 1) * step, 'where': where,
                      'peak_width_mm': 1e3 * float(w[k]), 'peak_ratio': float(w[k] / nominal_width),
                      'excess_width2_length_mm3': 1e9 * excess})
    figures = {
        'deposit_points': int(wet.sum()),
        'line_length_mm': 1e3 * length,
        'nominal_width_mm': 1e3 * nominal_width,
        'band': band,
        'width_mm': {'mean': 1e3 * float(w[covered].mean()), 'min': 1e3 * float(w[covered].min()),
                     'max': 1e3 * float(w.max())},
        'width_within_band_fraction': float(ok.mean()),
        'gap_length_mm': 1e3 * float((~covered).sum() * step),
        'gaps': [{'station_mm': 1e3 * a, 'length_mm': 1e3 * n} for a, n in gaps],
        'blobs': blobs,
        'lateral_deviation_mm': {'mean': 1e3 * float(lateral[wet].mean()),
                                 'p95': 1e3 * float(np.percentile(lateral[wet], 95)),
                                 'max': 1e3 * float(lateral[wet].max())},
        'start_station_mm': 1e3 * s_first, 'stop_station_mm': 1e3 * s_last,
    }
    prof = StationProfile(prof.station, prof.width, prof.passes, station[wet], lateral[wet])
    if closed:
        figures['closure'] = closure_overlap(station[wet], widths[wet], nominal_width, length)
    if standoff is not None:
        so = np.asarray(standoff, dtype=float)[wet]
        figures['standoff_mm'] = {'mean': 1e3 * float(so.mean()), 'min': 1e3 * float(so.min()),
                                  'max': 1e3 * float(so.max())}
    return figures, prof


def closure_overlap(station: np.ndarray, widths: np.ndarray, nominal_width: float, length: float) -> dict:
    """Where a loop's bead starts and ends (its section first and last at half the nominal one, i.e. the width
    at nominal / sqrt(2), in time order) and the overlap [mm] of the end past the start (negative: it stops
    short of the start). A start that rises and an end that falls over the same stretch, adding up to the
    full section there, have an overlap of 0."""
    half = widths >= nominal_width / np.sqrt(2.0)
    if not np.any(half):
        return {'start_station_mm': None, 'end_station_mm': None, 'overlap_mm': None}
    i, j = np.flatnonzero(half)[[0, -1]]
    unwrapped = np.unwrap(station, period=length)
    travelled = unwrapped[j] - unwrapped[i]  # the pass from the start to the end, along the loop
    return {'start_station_mm': 1e3 * float(station[i]), 'end_station_mm': 1e3 * float(station[j]),
            'overlap_mm': 1e3 * float(travelled - length)}
