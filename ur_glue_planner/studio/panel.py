"""The studio's control panel: what is in it and in which order (handles only; the studio wires the callbacks).

Above the tabs, blocks of fixed height (robot status, message log, where the keys go, legend), so that nothing in
the tabs moves when their text changes: the Run and Stop buttons stay where the user's pointer is.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import viser

from ur_glue_planner.studio.figures import FIGURES
from ur_glue_planner.studio.keys import KEYS_HTML
from ur_glue_planner.studio.legend import legend_entries, legend_html
from ur_glue_planner.studio.messages import log_html
from ur_glue_planner.studio.robot_status import status_html

HELP = ('**Keys** (seed 1): Up/Down rotate the tool about X, Left/Right about Y, by the step; '
        '**C** saves the orientation of the current waypoint, **N** goes to the next. A waypoint left without C '
        'is skipped by the plan. The arrow keys turn only the tool (the mouse turns the view); the line above the '
        'tabs says where the keys go; Reset view puts the view back where it started. Click the glass to add a '
        'waypoint after the selected one; click a marker to select it; drag the gizmo to move it on the glass or '
        'turn it.')
TIME_LABEL = 'Job time [s]'  # the whole job; the figures show the bead (their axes say which part)
LIVE_TEXT = '**Live viewer**: any robot publishing joint_states and robot_description.'
#: The page's hotkeys and the seed's key each one is.
KEYS = {'arrowup': 'up', 'arrowdown': 'down', 'arrowleft': 'left', 'arrowright': 'right', 'C': 'c', 'N': 'n'}


@dataclass
class Panel:
    """Handles of the panel's controls (None where the page has no job)."""

    robot_status: object
    log: object
    legend: object
    live_text: object = None
    clear_trail: object = None
    wp_info: object = None
    wp_select: object = None
    click_adds: object = None
    step: object = None
    orientation: object = None
    edits: object = None
    plan_button: object = None
    plan_info: object = None
    play: object = None
    time: object = None
    speed: object = None
    images: dict | None = None
    run_button: object = None
    stop_button: object = None
    progress: object = None
    run_info: object = None
    save_path: object = None
    save_button: object = None
    load_path: object = None
    load_button: object = None
    commands: dict | None = None
    reset_view: object = None


def build_panel(gui: viser.GuiApi, with_job: bool, live: bool, save_default: str) -> Panel:
    """Add the controls: the live viewer's few, or the job's four tabs (Teach, Plan, Run, File) and hotkeys."""
    p = Panel(robot_status=gui.add_html(status_html('waiting', '')), log=gui.add_html(log_html([])),
              legend=None)
    if not with_job:
        p.legend = gui.add_html(legend_html(legend_entries(False, live)))
        p.live_text = gui.add_markdown(LIVE_TEXT)
        p.clear_trail = gui.add_button('Clear tip path')
        p.reset_view = gui.add_button('Reset view')
        return p
    gui.add_html(KEYS_HTML)
    p.legend = gui.add_html(legend_html(legend_entries(True, live)))
    # The camera back where a new page puts it (keys held in the view can fly it anywhere, even out of the scene).
    p.reset_view = gui.add_button('Reset view')
    tabs = gui.add_tab_group()
    with tabs.add_tab('Teach'):
        p.wp_info = gui.add_markdown('')
        p.wp_select = gui.add_number('Waypoint', 1, min=1, step=1)
        p.click_adds = gui.add_checkbox('Click on glass adds a waypoint', True)
        p.step = gui.add_number('Step [deg]', 5.0, min=0.1, max=45.0, step=0.5)
        p.orientation = gui.add_button_group('Orientation', ('C: save', 'N: next'))
        p.edits = gui.add_button_group('Waypoint', ('earlier', 'later', 'delete', 'defaults'))
        gui.add_markdown(HELP)
    with tabs.add_tab('Plan'):
        p.plan_button = gui.add_button('Plan', color='blue')
        p.plan_info = gui.add_markdown('')
        p.play = gui.add_button_group('Playback', ('play', 'pause'))
        p.time = gui.add_slider(TIME_LABEL, 0.0, 1.0, 0.01, 0.0)
        p.speed = gui.add_slider('Speed', 0.1, 4.0, 0.1, 1.0)
        p.images = {name: gui.add_image(np.full((8, 8, 3), 255, np.uint8), label=name, visible=False)
                    for name in FIGURES}
    with tabs.add_tab('Run'):
        p.run_button = gui.add_button('Run', color='green')
        p.stop_button = gui.add_button('Stop', color='red')
        p.progress = gui.add_progress_bar(0.0)
        p.run_info = gui.add_markdown('')
    with tabs.add_tab('File'):
        p.save_path = gui.add_text('Save as', save_default)
        p.save_button = gui.add_button('Save')
        p.load_path = gui.add_text('Load', '')
        p.load_button = gui.add_button('Load')
    p.commands = {key: gui.add_command(f'key {key}', hotkey=hotkey) for hotkey, key in KEYS.items()}
    return p
