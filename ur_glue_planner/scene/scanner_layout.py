"""Where the cell's laser profile scanners hang: two over each edge of the nominal glass, looking down its normal.

Each scanner's laser line crosses the glass edge at right angles, from ``OUTSIDE`` beyond the edge to ``INSIDE``
within it, so one profile shows where the edge is (the in-plane placement) and the face's height and slope over
the bead (the bead runs 30 mm inside the edge). Eight such lines fix the part's placement (6 degrees of freedom)
with room to spare, and show its shape where the bead goes. :func:`scanner_layout` writes the ``scanners:`` block
of ``config/scenes/windshield.yaml`` (the cell's calibration: fixed numbers, whatever part comes in).
"""
from __future__ import annotations

import math

import numpy as np

from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD, WindshieldModel

STANDOFF = 0.2  # [m] emitter above the glass, along its normal (a mid-range profile scanner's working distance)
OUTSIDE, INSIDE = 0.02, 0.06  # [m] the line's reach beyond and within the edge
POINTS = 400  # beams per line: 0.2 mm apart on the glass
FRACTIONS = (0.3, 0.7)  # along each straight edge
NOISE = 5e-5  # [m] 1 sigma along a beam (a profile scanner on a cell's frame: tens of micrometres)
RATE = 5.0  # [Hz]
MAX_RANGE = 0.3  # [m] the scanners' measuring window ends here (the floor is out of range)
EDGES = ('left', 'top', 'right', 'bottom')  # corner i -> i + 1 of the default outline, the bead's order


def _world_tangent(model: WindshieldModel, uv: np.ndarray, direction_uv: np.ndarray) -> np.ndarray:
    """Unit world direction on the face at uv (2,) of a step along direction_uv (2,)."""
    h = 1e-5
    a = model.surface_point(*(uv - h * direction_uv))
    b = model.surface_point(*(uv + h * direction_uv))
    return (b - a) / np.linalg.norm(b - a)


def scanner_layout(model: WindshieldModel = DEFAULT_WINDSHIELD, targets: tuple[str, ...] = ('windshield',)) -> dict:
    """The ``scanners`` block (a dict ready for YAML) for the glass ``model`` as placed."""
    glass = model.glass.inset(0.0)
    corners = np.asarray(glass.corners)
    units = []
    for i, edge in enumerate(EDGES):
        inward = glass.normals[i]
        # the straight part of the edge: between the tangent points of the two corner arcs
        ta = glass.centers[i] - glass.radius * inward
        tb = glass.centers[(i + 1) % len(corners)] - glass.radius * inward
        for k, f in enumerate(FRACTIONS):
            on_edge = ta + f * (tb - ta)
            mid = on_edge + inward * (INSIDE - OUTSIDE) / 2.0
            normal = model.surface_normal(*mid)
            line = _world_tangent(model, mid, inward)
            line = line - (line @ normal) * normal
            line /= np.linalg.norm(line)
            origin = model.surface_point(*mid) + STANDOFF * normal
            half = (INSIDE + OUTSIDE) / 2.0
            units.append({'name': f'{edge}_{k + 1}', 'origin': [round(float(x), 6) for x in origin],
                          'direction': [round(float(x), 9) for x in -normal],
                          'line': [round(float(x), 9) for x in line],
                          'fov_deg': round(2.0 * math.degrees(math.atan(half / STANDOFF)), 4), 'points': POINTS})
    return {'targets': list(targets), 'max_range': MAX_RANGE, 'noise': NOISE, 'rate': RATE, 'units': units}
