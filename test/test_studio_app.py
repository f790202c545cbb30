"""The studio's page logic without a browser or ROS: picking, keys, the gizmo, plan and playback, save."""
import re
import threading

import numpy as np
import pytest
import yaml
from studio_browser import free_port, wait_until

from ur_common.paths import config_dir
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.studio import scene_view as sv
from ur_glue_planner.studio.app import Studio


@pytest.fixture(scope='module')
def studio():
    s = Studio(config_dir() / 'glue_job.yaml', port=free_port(), live=None)
    yield s
    s.close()


def test_a_ray_through_the_glass_adds_the_waypoint_there(studio):
    studio.load(config_dir() / 'glue_job.yaml')
    target = studio.glass.surface_point(-0.1, 0.2)
    origin = target + np.array([0.3, -0.4, 0.8])
    assert studio.add_at_ray(origin, target - origin)
    assert studio.teach.selected == 1 and len(studio.teach.waypoints) == 23
    assert np.linalg.norm(np.array(studio.teach.waypoints[1].position) - target) < 1e-9
    assert not studio.add_at_ray(origin, [0.0, 0.0, 1.0])
    assert studio.messages[-1] == 'the click missed the glass'


def test_gizmo_moves_along_the_glass_and_turns(studio):
    studio.load(config_dir() / 'glue_job.yaml')
    studio._edit(lambda s: s.select(3))
    uv, foot, normal = studio.glass.project(np.array(studio.teach.waypoints[3].position)[None])
    dragged = foot[0] + [0.02, 0.0, 0.0] + 0.01 * normal[0]  # off the glass a little
    turned = rotation_from_zyx_euler(0.0, 0.1, -1.0)
    assert studio.gizmo_released(3, dragged, sv.wxyz(turned))
    wp = studio.teach.waypoints[3]
    _, back, _ = studio.glass.project(np.array(wp.position)[None])
    assert np.linalg.norm(back[0] - wp.position) < 1e-9  # on the glass
    assert np.linalg.norm(np.array(wp.position) - foot[0]) == pytest.approx(0.02, abs=1e-3)
    assert np.allclose(wp.rotation(), turned, atol=1e-9) and not wp.saved
    before = studio.teach
    assert not studio.gizmo_released(3, [2.0, 0.0, 0.0], sv.wxyz(turned))  # off the glass: refused
    assert studio.teach == before


def test_reach_marks_an_unreachable_waypoint(studio):
    studio.load(config_dir() / 'glue_job.yaml')
    studio._edit(lambda s: s.with_step(10.0))
    for _ in range(8):  # tip turned 80 deg about Y: the dispenser body would go into the glass
        studio.key('right')
    wait_until(lambda: studio.reach_results[0] is not None and not studio.reach_results[0].reachable,
               'the reach check', timeout=30)
    assert studio.reach_results[0].reason.startswith('collision with the glass: dispenser')
    assert '**unreachable**: collision with the glass' in studio.panel.wp_info.content
    wait_until(lambda: tuple(studio._markers[0].color) == sv.RED, 'the red marker')  # markers: sphere, label, ...
    assert tuple(studio._markers[2].color) == sv.GREEN


def test_plan_playback_and_save(studio, tmp_path):
    studio.load(config_dir() / 'glue_job.yaml')
    plan = studio.plan_now()
    assert plan is not None and studio.timeline.duration == pytest.approx(plan.summary.total_duration)
    studio._on_play('play')
    # The clock plays (its wall seconds -> plan seconds are test_studio_playback's Clock tests, without a clock).
    wait_until(lambda: studio.clock.t > 0.3, 'the playback clock')
    studio._on_play('pause')
    path = studio.save(tmp_path / 'job.yaml')
    raw = yaml.safe_load(path.read_text())
    assert np.array_equal(np.array(raw['path']['waypoints']), studio.teach.planned_arrays()[0])


def test_a_run_result_stays_shown_while_its_thread_closes_its_client():
    """The run thread calls on_done, then closes its ROS client: the page loop must not write the progress line over
    the result meanwhile (a loaded machine's 'Run succeeded' was replaced by 'running bead: 100 %' once)."""
    import threading

    from ur_glue_planner.studio.ros_link import LiveRobot, RunResult

    live = LiveRobot()
    s = Studio(config_dir() / 'glue_job.yaml', port=free_port(), live=live)
    closing = threading.Event()
    try:
        with s._lock:
            s.run_progress = ('bead', 1.0, 0.0)
        live._run_thread = threading.Thread(target=closing.wait, daemon=True)  # the run thread, closing its client
        live._run_thread.start()
        s._on_run_done(RunResult(True, 0, 'all segments succeeded'), None)
        with s._lock:
            s._update_run_gui()
        assert live.running and s.panel.run_info.content == '**Run succeeded**: all segments succeeded'
    finally:
        closing.set()
        s.close()
        live.close()


def test_the_plan_text_counts_the_wait_from_the_click(studio):
    """The plan's text states the user's wait from the click (given to plan_now), not planning's own time."""
    import time
    plan = studio.plan_now(clicked=time.monotonic() - 20.0)  # a click 20 s ago: a loaded machine's wait
    assert plan is not None
    waited = float(re.search(r'ready ([0-9.]+) s after Plan was pressed', studio.panel.plan_info.content).group(1))
    assert 20.0 <= waited < 20.0 + 120.0 and plan.summary.planning_seconds < waited


class _Run:
    """A run the Stop click asks to end: records when it was asked, and the end it waits for."""

    def __init__(self) -> None:
        self.running = True
        self.asked = threading.Event()
        self.ended = threading.Event()

    def request_stop(self) -> None:
        self.asked.set()

    def stop_run(self) -> None:
        self.ended.wait(30.0)


def test_stop_asks_the_run_to_cancel_while_the_studio_is_busy():
    """A Stop click cancels the goal even while another thread holds the studio's lock (the page loop drawing the
    robot and the bead): its message and the wait for the run's end come after."""
    from ur_glue_planner.studio.messages import MessageLog
    from ur_glue_planner.studio.run_view import RunView

    class Busy(RunView):
        def __init__(self) -> None:
            self._lock = threading.RLock()
            self.live = _Run()
            self.log = MessageLog()

        def say(self, text: str) -> None:
            with self._lock:
                self.log.say(text)

    studio = Busy()
    release = threading.Event()
    held = threading.Event()

    def busy() -> None:
        with studio._lock:
            held.set()
            release.wait(30.0)
    holder = threading.Thread(target=busy, daemon=True)
    holder.start()
    assert held.wait(10.0)
    stop = threading.Thread(target=studio.stop_run, daemon=True)
    try:
        stop.start()
        assert studio.live.asked.wait(10.0), 'Stop waited for the studio lock before cancelling'
    finally:
        release.set()
        studio.live.ended.set()
        holder.join(10.0)
        stop.join(10.0)
    assert studio.log.history[-1] == 'stop: cancelling the goal'
