"""What a user saw go wrong in the studio's page (issue #26 point 7), in a real browser, without a robot.

Debian's headless chromium driven by Playwright against a studio with no ROS connection: arrow keys turn the tool
and not the view; after typing in the Waypoint field the keys reach the tool again, and the page says where they
go; a plan failing on an unreachable waypoint names it; the message box keeps its height and a new action clears
old errors; after Plan the selected waypoint's IK robot is drawn, after Load the old plan is gone; the legend and
the time axes are on the page. Running on a robot is test_studio_browser.py's.
"""
from __future__ import annotations

import numpy as np
import pytest
from studio_browser import free_port, launched_chromium, open_page, screenshot, set_camera, wait_until

from ur_common.paths import config_dir
from ur_glue_planner.studio.app import INITIAL_CAMERA, Studio
from ur_glue_planner.studio.messages import SHOWN

JOB = config_dir() / 'glue_job.yaml'
FRAMES_HELD = 15  # animation frames an arrow key is held: a tap of a quarter second at 60 frames a second


@pytest.fixture(scope='module')
def browser():
    with launched_chromium() as b:
        yield b


@pytest.fixture(scope='module')
def studio():
    s = Studio(JOB, port=free_port(), live=None)
    yield s
    s.close()


@pytest.fixture(scope='module')
def page(browser, studio):
    page, client = open_page(browser, studio)
    page.studio_client = client
    yield page
    page.close()


def _frames(page, n: int) -> None:
    """Let the page draw ``n`` animation frames (time passes in the page's own terms)."""
    for _ in range(n):
        page.evaluate('new Promise(done => requestAnimationFrame(done))')


def _settled(studio) -> None:
    """The studio has finished what the last key began: its refresh sets the Waypoint field (to the selected
    waypoint) under the studio's lock after the edit it shows, and one still running when a typed number arrived
    reset the field before the number's handler read it (a CI run waited 60 s for waypoint 3)."""
    with studio._lock:
        pass


def _keys_target(page) -> str:
    return page.locator('#studio-keys').get_attribute('data-target')


def _box_y(page, name: str) -> float:
    return page.get_by_role('button', name=name, exact=True).bounding_box()['y']


def test_an_arrow_key_turns_the_tool_and_not_the_view(studio, page):
    client = page.studio_client
    set_camera(client, np.array(INITIAL_CAMERA[0]) + [0.05, 0.1, 0.1], INITIAL_CAMERA[1])  # a pose it reports
    camera = np.array(client.camera.position)
    studio._edit(lambda s: s.select(0))
    page.evaluate('document.activeElement && document.activeElement.blur()')
    wait_until(lambda: _keys_target(page) == 'tool', 'the page to say the keys turn the tool')
    before = studio.teach.waypoints[0].orientation_zyx
    # A tap as a hand makes it (held for some frames): viser's camera turned 50 deg/s while an arrow was down.
    page.keyboard.down('ArrowUp')
    _frames(page, FRAMES_HELD)
    page.keyboard.up('ArrowUp')
    wait_until(lambda: studio.teach.waypoints[0].orientation_zyx != before, 'the tool to turn')
    _frames(page, 30)  # a camera still moving would have sent its pose by now (it sends within 20 ms)
    page.keyboard.press('c')  # and what the page sent before this key has arrived once the key has
    wait_until(lambda: studio.teach.waypoints[0].saved, 'C to save')
    assert np.allclose(client.camera.position, camera, atol=1e-6), (client.camera.position, camera)
    assert studio.teach.waypoints[0].orientation_zyx[2] == pytest.approx(before[2] + np.radians(5.0), abs=1e-12)


def test_reset_view_brings_the_camera_back_where_a_new_page_has_it(studio, page):
    client = page.studio_client
    set_camera(client, (3.0, -2.0, 0.5), (2.0, -2.0, 0.5))  # flown off, looking away from the cell
    page.get_by_role('button', name='Reset view', exact=True).click()
    wait_until(lambda: np.allclose(client.camera.position, INITIAL_CAMERA[0], atol=1e-6)
               and np.allclose(client.camera.look_at, INITIAL_CAMERA[1], atol=1e-6), 'the camera back')


def test_after_typing_a_waypoint_number_the_keys_turn_the_tool_again(studio, page):
    _settled(studio)
    field = page.get_by_label('Waypoint', exact=True)
    field.fill('3')
    wait_until(lambda: studio.teach.selected == 2, 'waypoint 3 selected from the field')
    wait_until(lambda: _keys_target(page) == 'field', 'the page to say the keys go to the field')
    assert 'Waypoint' in page.locator('#studio-keys').inner_text()
    screenshot(page, 'p1_keys_in_a_field')
    field.press('Enter')
    wait_until(lambda: _keys_target(page) == 'tool', 'Enter to give the keys back to the tool')
    before = studio.teach.waypoints[2].orientation_zyx
    page.keyboard.press('ArrowUp')  # turns waypoint 3's tool; it does not step the field to waypoint 4
    wait_until(lambda: studio.teach.waypoints[2].orientation_zyx != before, 'Up to turn the tool')
    page.keyboard.press('c')
    wait_until(lambda: studio.teach.waypoints[2].saved, 'C to save')
    assert studio.teach.selected == 2
    # C and N act from the number field too (it takes no letters): N there selects the next waypoint.
    _settled(studio)
    field.fill('7')
    wait_until(lambda: studio.teach.selected == 6, 'waypoint 7 selected from the field')
    field.press('n')
    wait_until(lambda: studio.teach.selected == 7, 'N from the field to select waypoint 8')
    wait_until(lambda: _keys_target(page) == 'tool', 'the keys back with the tool')


def test_a_plan_failing_on_an_unreachable_waypoint_names_it_and_nothing_moves(studio, page):
    page.get_by_role('tab', name='Plan').click()
    plan_y = _box_y(page, 'Plan')
    original = studio.teach.waypoints[12].position
    moved = np.array(original) + [0.09, 0.045, 0.0]  # a few cm beyond the arm's reach, on the glass
    studio._edit(lambda s: s.move(12, studio.glass.project(moved[None])[1][0]))
    page.get_by_role('button', name='Plan', exact=True).click()
    wait_until(lambda: any(m.startswith('planning failed') for m in list(studio.messages)), 'the plan to fail',
               timeout=120)
    failure = next(m for m in studio.messages if m.startswith('planning failed'))
    assert failure.startswith('planning failed: waypoint 13: out of reach (') and failure.endswith(' mm)'), failure
    wait_until(lambda: page.get_by_text('waypoint 13: out of reach').count() > 0, 'the page to name the waypoint')
    assert page.get_by_text('IK branch').count() == 0  # not the planner's 20 lines
    screenshot(page, 'p2_plan_failed')
    for k in range(2 * SHOWN):
        studio.say(f'filler line {k}')
    wait_until(lambda: page.get_by_text(f'filler line {2 * SHOWN - 1}').count() > 0, 'the lines on the page')
    assert _box_y(page, 'Plan') == plan_y  # the box keeps its height: the button stays under the pointer
    # A new plan clears the old error: the waypoint back where it was, Plan again.
    studio._edit(lambda s: s.move(12, original))
    page.get_by_role('button', name='Plan', exact=True).click()
    wait_until(lambda: studio.plan is not None, 'the plan', timeout=120)
    wait_until(lambda: page.get_by_text('planned: bead').count() > 0, 'the page to say planned')
    assert page.get_by_text('waypoint 13: out of reach').count() == 0
    assert page.get_by_text('filler line').count() == 0
    assert _box_y(page, 'Plan') == plan_y


def test_after_plan_the_ik_robot_shows_the_selected_waypoint_and_load_clears_the_plan(studio, page):
    assert studio.plan is not None  # the previous test's
    wp = studio.teach.current()
    tip = studio._model_view.frames['dispenser_tip']
    wait_until(lambda: np.allclose(tip.position, wp.position, atol=1e-6), 'the IK robot at the selected waypoint')
    assert studio.mode == 'teach' and tip.visible
    figures = page.locator('img[src^="blob:"]')  # the figures; viser's own icons are inline SVG
    wait_until(lambda: figures.count() == 4 and all(img.is_visible() for img in figures.all()), 'the figures')
    # The legend and the time axes: the slider spans the job, the figures the bead, and both say so.
    for text in ('IK of the selected waypoint / plan playback', 'planned bead, by planned tip speed',
                 'Job time [s]', 'the figures show the bead'):
        assert page.get_by_text(text).first.is_visible(), text
    assert page.get_by_text('executed tip path').count() == 0  # no robot: nothing executed to show
    screenshot(page, 'p3_planned')
    page.get_by_role('tab', name='File').click()
    page.locator('input:visible').nth(1).fill(str(JOB))  # the File tab's fields: Save as, Load
    page.get_by_role('button', name='Load', exact=True).click()
    wait_until(lambda: studio.messages[-1].startswith(f'loaded {JOB}'), 'the job to load')
    page.get_by_role('tab', name='Plan').click()
    wait_until(lambda: page.get_by_text('No plan yet').count() > 0, 'the Plan tab to say there is no plan')
    wait_until(lambda: not any(img.is_visible() for img in figures.all()), 'the old figures to go')
    assert studio.plan is None and studio._planned_bead is None
    screenshot(page, 'p4_loaded')
