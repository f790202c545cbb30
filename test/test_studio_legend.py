"""The legend of the studio's page: an entry for each robot and path it can show, in the colours they are drawn."""
import numpy as np

from ur_glue_planner.studio.legend import (
    DEPOSIT_COLOR,
    EXECUTED_COLOR,
    MEASURED_COLOR,
    MODEL_TINT,
    NOMINAL_PATH_COLOR,
    SCAN_COLOR,
    SPEED_SCALE,
    css,
    legend_entries,
    legend_html,
    speed_gradient,
)
from ur_glue_planner.studio.playback import speed_colors
from ur_glue_planner.studio.robot_geometry import LINK_COLOR, TOOL_COLOR


def test_two_robots_and_three_paths_with_a_job_and_a_robot():
    entries = {e.key: e for e in legend_entries(True, True, tcp_speed=0.15)}
    assert list(entries) == ['live', 'model', 'planned', 'executed', 'deposited', 'scan', 'nominal']
    assert css(SCAN_COLOR) in entries['scan'].background and css(MEASURED_COLOR) in entries['scan'].background
    assert entries['nominal'].background == css(NOMINAL_PATH_COLOR)
    assert entries['model'].background == css(MODEL_TINT)
    assert entries['executed'].background == css(EXECUTED_COLOR)
    assert entries['deposited'].background == css(DEPOSIT_COLOR)
    assert css(LINK_COLOR) in entries['live'].background and css(TOOL_COLOR) in entries['live'].background
    assert entries['planned'].label.endswith(f'0 to {SPEED_SCALE * 0.15:.3f} m/s')


def test_what_each_page_can_show():
    assert [e.key for e in legend_entries(True, False)] == ['model', 'planned']  # no ROS: teaching and preview
    assert [e.key for e in legend_entries(False, True)] == ['live', 'executed', 'deposited']  # live viewer


def test_the_speed_swatch_is_the_beads_colour_scale():
    slow, fast = (css(c) for c in speed_colors(np.array([0.0, 1.0]), 1.0) * 255.0)
    gradient = speed_gradient()
    assert gradient.startswith(f'linear-gradient(to right, {slow}') and gradient.endswith(f'{fast})')
    markup = legend_html(legend_entries(True, True, 0.15))
    assert markup.count('class="studio-legend-') == 7 and 'executed tip path' in markup
