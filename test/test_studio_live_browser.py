"""The studio as a live viewer in a real browser: no job, a robot in its own process, its motion streamed to the page,
the path of its dispenser tip traced, and the robot's status (awaited, live, gone) on the page.

Its own module, so that no other studio, page or in-process simulator runs beside it. The update rate itself
(>= 30 per second) is measured by bench/bench_studio.py (`make bench`), not here: a timed assertion fails whenever
another job on this 2-core machine takes the CPU.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from ament_index_python.packages import get_package_prefix
from studio_browser import (
    free_port,
    launched_chromium,
    open_page,
    pump_until,
    screenshot,
    set_camera,
    wait_until,
)

from ur_glue_planner.client import URClient
from ur_glue_planner.studio.app import Studio
from ur_glue_planner.studio.ros_link import LiveRobot
from ur_sim_driver.description.params import joint_names


@pytest.fixture(scope='module')
def browser():
    with launched_chromium() as b:
        yield b


def _ur_sim_process() -> subprocess.Popen:
    exe = Path(get_package_prefix('ur_sim_driver')) / 'lib' / 'ur_sim_driver' / 'ur_sim'
    return subprocess.Popen([str(exe), '--ros-args', '-p', 'ur_type:=ur5', '-p', 'tool:=dispenser',
                             '-p', 'namespace:=/live'], start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def _status(page) -> tuple[str, str]:
    """(state, text) of the robot status line on the page."""
    status = page.locator('.studio-robot-status')
    return status.get_attribute('data-state'), status.inner_text().split('Robot: ', 1)[-1]


def _stop(sim: subprocess.Popen) -> None:
    if sim.poll() is None:
        os.killpg(sim.pid, signal.SIGINT)
    try:
        sim.wait(timeout=20)
    except subprocess.TimeoutExpired:
        sim.kill()


def test_without_a_job_the_studio_is_a_live_viewer(browser):
    # As deployed: the robot (here ur_sim, real time) in its own process, the studio in another; a seed 2 style
    # namespace. The page must receive the robot's motion as it happens, throughout the move.
    # This process now plays the ur_glue_studio process, which keeps Python's default GIL switch interval
    # (conftest shortens it for the in-process simulators of the other tests, which would slow the page here).
    interval = sys.getswitchinterval()
    sys.setswitchinterval(0.005)
    live = LiveRobot('/live')
    viewer = Studio(None, port=free_port(), live=live)
    sim = None
    try:
        # A small page: software rendering of a large one takes a core.
        page, client = open_page(browser, viewer, viewport={'width': 640, 'height': 400})
        # Started before the robot: the page says what it waits for (it was blank).
        wait_until(lambda: _status(page) == ('waiting', 'waiting for /live/joint_states and /live/robot_description'),
                   'the page to say it waits for the robot')
        sim = _ur_sim_process()
        wait_until(lambda: viewer.live_view.view is not None and viewer.live_updates > 0, 'the live robot')
        wait_until(lambda: _status(page)[0] == 'live', 'the page to say the robot is live')
        assert viewer.sjob is None
        set_camera(client, (1.2, -1.0, 1.0), (0.0, 0.3, 0.4))
        with URClient(namespace='/live', timeout=30.0) as ur:
            q0 = ur.joint_state().q
            delta = np.array([0.8, 0.3, -0.4, 0.3, 0.5, 0.6])
            goal = ur.send_joint_configuration(q0 + delta, end_time=8.0, wait=False)
            page.wait_for_timeout(1000)  # deliver what arrived before counting
            page.ws_frames.clear()
            updates0, trail0 = viewer.live_updates, len(viewer.live_view.trail)

            def progress() -> float:  # of the move, by where the robot is (0 at the start, 1 at the end)
                return float(np.dot(ur.joint_state().q - q0, delta) / np.dot(delta, delta))
            # Streamed as it happens, judged by the robot's progress and not by the clock: robot updates reach the
            # page, and the tip path grows, in the first half of the move and again in the second.
            pump_until(page, lambda: progress() >= 0.5, 'the robot halfway', timeout=60)
            half = (len(page.ws_frames), viewer.live_updates - updates0, len(viewer.live_view.trail) - trail0)
            pump_until(page, lambda: goal.done, 'the move to end', timeout=60)
            assert goal.wait().succeeded
            q_end = ur.joint_state().q
        end = (len(page.ws_frames), viewer.live_updates - updates0, len(viewer.live_view.trail) - trail0)
        report = f'(page messages, robot updates, tip path points): halfway {half}, at the end {end}'
        assert 0 < half[0] < end[0], report  # streamed throughout, not only at the end
        # The tip path drawn as it went: a point for each robot update that moved the tip by more than 0.5 mm.
        # How many there are follows the update rate, which is bench_studio's (`make bench`).
        assert 0 < half[2] < end[2], report
        # It traces the dispenser's tip, where the bead is laid, not the flange one tool length above it.
        assert viewer.live_view.tip_frame == 'dispenser_tip'
        robot = viewer.live_view.view.robot
        wait_until(lambda: np.linalg.norm(viewer.live_view.trail[-1] - robot.frame_position(
            'dispenser_tip', joint_names(), q_end)) < 1e-3, 'the tip path to end at the dispenser tip')
        assert np.linalg.norm(viewer.live_view.trail[-1] - robot.frame_position('tool0', joint_names(), q_end)) > 0.15
        wait_until(lambda: page.get_by_text('Live viewer').count() > 0, 'the live viewer text')
        wait_until(lambda: page.get_by_text('traces dispenser_tip').count() > 0, 'the traced frame named')
        screenshot(page, '6_live_viewer')
        # The robot goes away: its last pose stays drawn, and the page says it is gone.
        _stop(sim)
        wait_until(lambda: _status(page)[0] == 'gone', 'the page to say the robot is gone', timeout=30)
        assert _status(page)[1].startswith('robot gone: no /live/joint_states for ')
        screenshot(page, '7_robot_gone')
        page.close()
    finally:
        viewer.close()
        live.close()
        sys.setswitchinterval(interval)
        if sim is not None:
            _stop(sim)
