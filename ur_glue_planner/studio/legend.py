"""The colours of what the studio draws, and the legend that names them.

Two robots can be on the page: the live one (its own colours, from /robot_description) and the job's model, tinted
blue and translucent, which shows the IK solution of the selected waypoint or plays the plan. Three paths: the
planned bead coloured by planned tip speed, the executed tip path (red) and the deposited bead (amber points); with
the cell's scanners, the measured part: their points, the measured glass, and the bead's line on the nominal glass
beside the planned (corrected) bead.
"""
from __future__ import annotations

import html
from dataclasses import dataclass

import numpy as np

from ur_glue_planner.studio.playback import speed_colors
from ur_glue_planner.studio.robot_geometry import LINK_COLOR, TOOL_COLOR

MODEL_TINT = (150, 90, 220)  # the IK / playback robot: violet, apart from the light blue glass
MODEL_OPACITY = 0.5
EXECUTED_COLOR = (230, 30, 30)  # the tip path the live robot traced
DEPOSIT_COLOR = (240, 160, 20)  # the simulated bead as deposited
SCAN_COLOR = (20, 170, 90)  # the part scanners' points
MEASURED_COLOR = (250, 200, 120)  # the glass as measured (translucent over the nominal glass)
NOMINAL_PATH_COLOR = (120, 120, 120)  # the bead's line on the nominal glass, before the measurement moved it
SPEED_SCALE = 1.1  # the planned bead's colours span 0 .. SPEED_SCALE x the commanded tip speed


@dataclass(frozen=True)
class LegendEntry:
    """One line of the legend: ``label`` beside a swatch drawn with the CSS ``background``."""

    key: str
    label: str
    background: str


def css(rgb) -> str:
    """CSS colour of an RGB triple in 0..255."""
    r, g, b = (int(round(v)) for v in rgb)
    return f'rgb({r},{g},{b})'


def speed_gradient(stops: int = 6) -> str:
    """CSS gradient of the planned bead's colour scale, slow (left) to fast (right)."""
    colors = speed_colors(np.linspace(0.0, 1.0, stops), 1.0) * 255.0
    return f'linear-gradient(to right, {", ".join(css(c) for c in colors)})'


def legend_entries(with_job: bool, live: bool, tcp_speed: float | None = None) -> list[LegendEntry]:
    """What the page can show, in the order of the legend.

    Args:
        with_job: A job is loaded (its model robot and planned bead are drawn).
        live: A ROS connection (the live robot, its tip path, the simulated bead).
        tcp_speed: The job's commanded tip speed [m/s] (the top of the colour scale is SPEED_SCALE x it).
    """
    entries = []
    if live:
        entries.append(LegendEntry('live', 'live robot (/joint_states)',
                                   f'linear-gradient(to right, {css(LINK_COLOR)} 60%, {css(TOOL_COLOR)} 60%)'))
    if with_job:
        entries.append(LegendEntry('model', 'IK of the selected waypoint / plan playback', css(MODEL_TINT)))
        top = f' 0 to {SPEED_SCALE * tcp_speed:.3f} m/s' if tcp_speed is not None else ''
        entries.append(LegendEntry('planned', f'planned bead, by planned tip speed{top}', speed_gradient()))
    if live:
        entries.append(LegendEntry('executed', 'executed tip path', css(EXECUTED_COLOR)))
        entries.append(LegendEntry('deposited', 'deposited bead (simulation)', css(DEPOSIT_COLOR)))
    if live and with_job:  # a plan on a measured part (where the cell has scanners)
        entries.append(LegendEntry('scan', 'part scanners\' points, measured glass', f'linear-gradient(to right, '
                                   f'{css(SCAN_COLOR)} 50%, {css(MEASURED_COLOR)} 50%)'))
        entries.append(LegendEntry('nominal', 'bead line on the nominal glass (before the measurement)',
                                   css(NOMINAL_PATH_COLOR)))
    return entries


def legend_html(entries: list[LegendEntry]) -> str:
    """The legend as compact HTML: a swatch and a label per entry."""
    rows = ''.join(
        f'<div class="studio-legend-{e.key}" style="display:flex;align-items:center;gap:0.4em">'
        f'<span style="display:inline-block;width:2.2em;height:0.7em;border-radius:2px;background:{e.background}">'
        f'</span>{html.escape(e.label)}</div>' for e in entries)
    return f'<div class="studio-legend" style="font-size:0.8em;line-height:1.3em">{rows}</div>'
