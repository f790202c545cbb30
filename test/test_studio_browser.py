"""The studio in a real browser (Debian's headless chromium, driven by Playwright) against an in-process ur_sim.

Stages, each with a screenshot under out/studio_test/: a click on the glass adds a waypoint at the surface point
under that pixel; the keys turn a waypoint's orientation by the step and C saves it; Save writes the taught job;
Plan measures the part with the cell's scanners, shows it and the seed's figures and plays; Run executes on ur_sim
and reports success while the page draws the live robot's tip path, its buttons staying put; a second run uses the
same client and waits before the bead as long as the first bead's delivery needed; Stop cancels; a new plan clears
the executed path. The live viewer without a job is in test_studio_live_browser.py, the page's own behaviour without
a robot in test_studio_page_browser.py.
"""
from __future__ import annotations

import os
import re
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from sim_harness import running_sim
from studio_browser import (
    VIEWPORT,
    free_port,
    launched_chromium,
    open_page,
    pixel_ray,
    project,
    pump_until,
    screenshot,
    set_camera,
    wait_until,
)

from ur_common.paths import config_dir
from ur_glue_planner.execution.client import delivery_margin
from ur_glue_planner.execution.run import BEAD_DELIVERY
from ur_glue_planner.studio.app import INITIAL_CAMERA, Studio
from ur_glue_planner.studio.ros_link import LiveRobot
from ur_glue_planner.studio.run_client import NODE_NAME, bead_margin

JOB = config_dir() / 'glue_job.yaml'
RTF = 1.0


@pytest.fixture(scope='module')
def sim():
    params = yaml.safe_load((config_dir() / 'ur_sim_windshield.yaml').read_text())['/**']['ros__parameters']
    # Real time: as fast as possible, the in-process simulation would leave the page's server little CPU.
    params['real_time_factor'] = RTF
    with running_sim(**params) as h:
        yield h


@pytest.fixture(scope='module')
def studio(sim, tmp_path_factory):
    live = LiveRobot('', context=sim.client.context)
    s = Studio(JOB, port=free_port(), live=live, save_path=tmp_path_factory.mktemp('studio') / 'taught.yaml')
    yield s
    s.close()
    live.close()


@pytest.fixture(scope='module')
def page(browser, studio):
    page, client = open_page(browser, studio)
    page.studio_client = client
    yield page
    page.close()


def _tab(page, name: str) -> None:
    page.get_by_role('tab', name=name).click()


def test_click_on_the_glass_adds_a_waypoint_at_the_surface_point(studio, page):
    client = page.studio_client
    glass = studio.glass
    target = glass.surface_point(0.05, 0.3)
    normal = glass.surface_normal(0.05, 0.3)
    # A camera 0.6 m above the glass looking down its normal: one pixel is about 1 mm there.
    set_camera(client, target + 0.6 * normal + [0.0, -0.05, 0.0], target, up=(0.0, 1.0, 0.0))
    w, h = VIEWPORT['width'], VIEWPORT['height']
    x, y = (round(v) for v in project(client, target, w, h))
    origin, direction = pixel_ray(client, x, y, w, h)
    hit = target  # where that pixel's ray meets the glass: the surface point nearest the ray, iterated
    for _ in range(5):
        t = np.dot(hit - origin, direction)
        hit = studio.glass.project((origin + t * direction)[None])[1][0]
    n_before = len(studio.teach.waypoints)
    studio._edit(lambda s: s.select(0))
    # The page may still be loading the scene when the camera is set; a click that reaches no mesh is lost, so
    # click again until the studio has the waypoint (a click that reached the glass is answered within ms).
    deadline = time.monotonic() + 60.0
    while len(studio.teach.waypoints) == n_before:
        assert time.monotonic() < deadline, 'the click never reached the studio'
        page.mouse.move(x, y)
        page.mouse.click(x, y)
        try:
            wait_until(lambda: len(studio.teach.waypoints) > n_before, 'the new waypoint', timeout=5.0)
        except TimeoutError:
            assert not any('missed the glass' in m for m in studio.messages), studio.messages
    assert len(studio.teach.waypoints) == n_before + 1
    added = np.array(studio.teach.waypoints[1].position)  # after the selected (first) one
    assert studio.teach.selected == 1
    assert np.linalg.norm(added - hit) < 0.002, f'{added} vs expected {hit}'
    _, foot, _ = studio.glass.project(added[None])
    assert np.linalg.norm(foot[0] - added) < 0.001  # on the glass
    wait_until(lambda: page.get_by_text('Waypoint 2').count() > 0, 'the page to show the new waypoint')
    screenshot(page, '1_teach_click')


def test_keys_turn_the_orientation_by_the_step_and_c_saves(studio, page):
    set_camera(page.studio_client, *INITIAL_CAMERA)
    studio._edit(lambda s: s.select(4))
    step = page.get_by_label('Step [deg]')
    step.fill('2.5')
    step.press('Enter')
    wait_until(lambda: studio.teach.step_deg == 2.5, 'the step setting')
    # Keys go to the page, not to the step field (where the arrows would change the number).
    page.evaluate('document.activeElement && document.activeElement.blur()')
    before = studio.teach.waypoints[4]
    for key in ('ArrowUp', 'ArrowUp', 'ArrowUp', 'ArrowLeft'):
        page.keyboard.press(key)
    wait_until(lambda: np.isclose(studio.teach.waypoints[4].orientation_zyx[2] - before.orientation_zyx[2],
                                  np.radians(7.5)), 'three Up presses')
    wait_until(lambda: np.isclose(studio.teach.waypoints[4].orientation_zyx[1] - before.orientation_zyx[1],
                                  -np.radians(2.5)), 'one Left press')
    assert not studio.teach.waypoints[4].saved
    assert 4 in studio.teach.skipped_indices()
    page.keyboard.press('c')
    wait_until(lambda: studio.teach.waypoints[4].saved, 'C to save the orientation')
    page.keyboard.press('n')
    wait_until(lambda: studio.teach.selected == 5, 'N to select the next waypoint')
    zyx = studio.teach.waypoints[4].orientation_zyx
    assert zyx[0] == before.orientation_zyx[0]
    assert zyx[1] == pytest.approx(before.orientation_zyx[1] - np.radians(2.5), abs=1e-12)
    assert zyx[2] == pytest.approx(before.orientation_zyx[2] + np.radians(7.5), abs=1e-12)
    screenshot(page, '2_teach_keys')


def test_save_writes_the_taught_job(studio, page):
    _tab(page, 'File')
    path = studio._save_default
    if os.path.exists(path):
        os.remove(path)
    page.get_by_role('button', name='Save', exact=True).click()
    wait_until(lambda: os.path.exists(path), 'the saved job file')
    raw = wait_until(lambda: yaml.safe_load(open(path).read()), 'the job file content')
    positions, zyx = studio.teach.planned_arrays()
    assert np.array_equal(np.array(raw['path']['waypoints']), positions)
    assert np.array_equal(np.array(raw['path']['orientation_zyx']), zyx)
    assert len(positions) == 23 - 1  # the clicked waypoint was never saved with C: skipped
    original = yaml.safe_load(JOB.read_text())
    assert {k: v for k, v in raw.items() if k != 'path'} == {k: v for k, v in original.items() if k != 'path'}
    row = studio.teach.planned_indices().index(4)  # the waypoint turned with the keys
    assert raw['path']['orientation_zyx'][row][2] == pytest.approx(-np.pi / 3 + np.radians(7.5), abs=1e-12)
    wait_until(lambda: page.get_by_text('saved 22 waypoints').count() > 0, 'the page to confirm the save')
    screenshot(page, '3_save')
    # Load it back through the page: the saved waypoints, all saved.
    page.locator('input:visible').nth(1).fill(str(path))  # the File tab's fields: Save as, Load (no labels)
    page.get_by_role('button', name='Load', exact=True).click()
    # The load replaces the job and then the taught state: the status line it writes last says it is done (sjob
    # alone can be read between the two).
    wait_until(lambda: any(m.startswith(f'loaded {path}') for m in list(studio.messages)), 'the file to load')
    assert studio.sjob.path == Path(path)
    assert np.array_equal(studio.teach.planned_arrays()[0], positions)
    assert np.array_equal(studio.teach.planned_arrays()[1], zyx) and not studio.teach.skipped_indices()


def test_plan_shows_the_figures_and_plays(studio, page):
    _tab(page, 'Plan')
    wait_until(lambda: studio.live.scan() is not None, "the cell's part scan")
    page.get_by_role('button', name='Plan', exact=True).click()
    wait_until(lambda: studio.plan is not None, 'the plan', timeout=120)
    # planned on the part as the cell's scanners measured it (the nominal one here), which the page shows: their
    # points, the measured glass and the bead's line on the nominal glass, with what the fit found in the messages
    found = studio.plan.part
    assert found is not None and np.abs(found.offset).max() < 3e-4
    drawn = ['/part/scan', '/part/measured_glass', '/part/nominal_line']
    wait_until(lambda: [h.name for h in studio.part_view.handles] == drawn, 'the measured part drawn')
    wait_until(lambda: page.get_by_text('part measured: offset').count() > 0, 'the measurement in the messages')
    figures = page.locator('img[src^="blob:"]')  # the figures; viser's own icons are inline SVG
    wait_until(lambda: figures.count() == 4 and all(img.is_visible() for img in figures.all()), 'the four figures')
    wait_until(lambda: page.get_by_text('Planned TCP speed').count() > 0, 'the speed figures')
    page.get_by_role('button', name='play').click()
    t0 = studio.clock.t
    wait_until(lambda: studio.clock.t > t0 + 0.5, 'the playback to advance')
    page.get_by_role('button', name='pause').click()
    wait_until(lambda: not studio.clock.playing, 'pause')
    # Scrub: the time field beside the slider (the Plan tab's number fields: time, speed).
    time_field = page.locator('input:visible').nth(0)
    sent = len(page.ws_frames)
    time_field.fill('12.5')
    time_field.press('Enter')
    wait_until(lambda: abs(studio.clock.t - 12.5) < 1e-9, 'the scrub to 12.5 s')
    assert studio.timeline.segment_at(studio.clock.t) == 'bead'
    pump_until(page, lambda: len(page.ws_frames) > sent, 'the robot pose at 12.5 s to reach the page', 30)
    screenshot(page, '4_plan')


def _button_y(page, name: str) -> float:
    return page.get_by_role('button', name=name, exact=True).bounding_box()['y']


def test_run_on_ur_sim_succeeds_with_the_robot_live_in_the_page(studio, page, sim):
    _tab(page, 'Run')
    page.get_by_role('button', name='Run', exact=True).click()
    wait_until(lambda: studio.live.running, 'the run to start')
    # The Run and Stop buttons stay where they are while the run's messages come (a Stop click once missed).
    places = set()

    def finished() -> bool:
        places.add((_button_y(page, 'Run'), _button_y(page, 'Stop')))
        return not studio.live.running
    pump_until(page, finished, 'the run to finish', timeout=180)
    assert studio.run_result is not None and studio.run_result.succeeded, studio.run_result
    assert studio.run_result.error_code == 0
    wait_until(lambda: page.get_by_text('Run succeeded').count() > 0, 'the page to report success')
    places.add((_button_y(page, 'Run'), _button_y(page, 'Stop')))
    assert len(places) == 1, places
    # The executed tip path, drawn as it went: judged by its length, not by its number of points (one per robot
    # update that reached the studio, which follows the machine's load). The bead alone is 2.2 m (2.18 m even
    # sampled once a second); the moves to and from it add more.
    trail = np.array(studio.live_view.trail)
    length = float(np.linalg.norm(np.diff(trail, axis=0), axis=1).sum()) if len(trail) > 1 else 0.0
    assert length > 2.0, f'tip path: {len(trail)} points, {length:.3f} m'
    # The glue gun was switched and the simulated bead, about 2.2 m at one point per mm, is shown on the glass.
    wait_until(lambda: studio.bead_points_drawn > 1500, 'the bead in the page')
    # After the run, the IK robot of the selected waypoint is drawn again beside the live one.
    assert studio.mode == 'teach' and studio._model_view.frames['dispenser_tip'].visible
    screenshot(page, '5_run')


def _logged(lines: list[str], pattern: str) -> float:
    """The number in the first line matching ``pattern`` (one group)."""
    return float(next(m.group(1) for m in (re.search(pattern, line) for line in lines) if m))


def test_a_second_run_uses_the_same_client_and_waits_as_the_last_bead_needed(studio, page, sim, capfd):
    ur = studio.live.client
    assert ur is not None and ur.runs == 1
    # A short goal answered slowly, as a busy machine answers one now and then: the rule of a new client
    # (4 x, scaled to the bead's points) made that a wait of 10 s before the bead.
    ur.goal_answers.append((0.3, 95))
    sent, said = len(ur.goal_answers), len(studio.messages)
    page.get_by_role('button', name='Run', exact=True).click()
    wait_until(lambda: studio.live.running, 'the run to start')
    wait_until(lambda: not studio.live.running, 'the run to finish', timeout=180)
    assert studio.run_result is not None and studio.run_result.succeeded, studio.run_result
    assert studio.live.client is ur and ur.runs == 2
    assert sim.client.get_node_names().count(NODE_NAME) == 1  # no node made per run
    # rcl's warning when a node is made under a name a live node of the process has (each Run used to log it)
    assert 'Publisher already registered' not in capfd.readouterr().err
    lines = studio.messages[said:]
    points = int(_logged(lines, r'^bead: (\d+) points'))
    t_on = _logged(lines, r'on at t = (-?[0-9.]+) s')
    ahead = _logged(lines, r'its start stamped (-?[0-9.]+) s ahead')
    bead = next(k for k in range(sent, len(ur.goal_answers)) if ur.goal_answers[k][1] == points)
    before = ur.goal_answers[:bead]
    assert delivery_margin(before, BEAD_DELIVERY, points) > 9.0  # what a new client would have waited
    lead = 0.1 + max(0.0, -t_on)
    expected = lead + bead_margin(before, BEAD_DELIVERY, points)
    # Stamped from the earlier bead's delivery (the log rounds to 0.1 s; robot time runs at the wall's pace).
    assert expected - 0.1 <= ahead <= 1.2 * expected + 0.1, (ahead, expected, before)


def test_stop_cancels_the_running_goal(studio, page, sim):
    _tab(page, 'Run')
    page.get_by_role('button', name='Run', exact=True).click()
    # The run before this one left its result and progress: the click has arrived once the result is cleared.
    wait_until(lambda: studio.run_result is None and studio.run_progress[0] is not None, 'the first feedback')
    page.get_by_role('button', name='Stop', exact=True).click()
    wait_until(lambda: studio.run_result is not None, 'the run to end', timeout=60)
    assert not studio.run_result.succeeded and studio.run_result.message.startswith('stopped')
    wait_until(lambda: sim.sim.jtc.active_token is None, 'the controller to hold')
    assert studio.live.client.runs == 3


def test_a_new_plan_clears_the_executed_path_and_the_bead(studio, page):
    wait_until(lambda: studio.live_view.pieces_drawn > 0 and studio.bead_points_drawn > 0,
               'the executed path and the bead of the runs')
    old = studio.plan
    _tab(page, 'Plan')
    page.get_by_role('button', name='Plan', exact=True).click()
    wait_until(lambda: studio.plan is not None and studio.plan is not old, 'the new plan', timeout=120)
    # The page loop may have begun the next path already: at most the tip where the arm rests, which draws nothing
    with studio._lock:
        assert studio.live_view.pieces_drawn == 0 and len(studio.live_view.trail) <= 1
        assert studio.bead_points_drawn == 0  # the runs' bead was laid for the plan before
    wp = studio.teach.current()  # and the IK robot at the selected waypoint, not the plan's start
    wait_until(lambda: np.allclose(studio._model_view.frames['dispenser_tip'].position, wp.position, atol=1e-6),
               'the IK robot at the selected waypoint')
    for text in ('live robot (/joint_states)', 'executed tip path', 'deposited bead (simulation)'):
        assert page.get_by_text(text).first.is_visible(), text


@pytest.fixture(scope='module')
def browser():
    with launched_chromium() as b:
        yield b
