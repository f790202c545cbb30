"""The deposited bead in the page (live_view.py), without ROS: drawn as it grows, new deposits only."""
from __future__ import annotations

import numpy as np
import pytest
import viser
from studio_browser import free_port

from ur_glue_planner.execution.bead_listener import BeadPoints
from ur_glue_planner.studio.live_view import LiveView


class _Sim:
    """The bead messages as ur_sim sends them: the whole bead so far each time."""

    def __init__(self) -> None:
        self.beads_received = 0
        self._bead: BeadPoints | None = None
        self.reads = 0  # whole beads read from a message

    def publish(self, n: int, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        points = np.cumsum(rng.uniform(0.0, 1e-3, (n, 3)), axis=0)
        self._bead = BeadPoints(points, np.full(n, 0.004), np.full(n, 0.003), np.arange(n) * 2e-3)
        self.beads_received += 1

    def bead(self) -> tuple[int, BeadPoints | None]:
        self.reads += 1
        return self.beads_received, self._bead


@pytest.fixture(scope='module')
def server():
    s = viser.ViserServer(host='127.0.0.1', port=free_port(), verbose=False)
    yield s
    s.stop()


def _sent(view: LiveView) -> list[int]:
    return [len(piece.points) for piece in view.bead_pieces]


def test_a_growing_bead_sends_only_its_new_deposits(server):
    sim = _Sim()
    view = LiveView(server, sim)
    for n in (50, 120, 120, 400):  # the third message: no new deposit (the flow has stopped)
        sim.publish(n)
        view._draw_bead()
    assert _sent(view) == [50, 70, 280] and view.bead_points_drawn == 400
    drawn = np.vstack([piece.points for piece in view.bead_pieces])
    assert np.allclose(drawn, sim.bead()[1].points, atol=1e-6)  # float32 on the page
    reads = sim.reads
    for _ in range(5):  # page ticks without a new message read nothing
        view._draw_bead()
    assert sim.reads == reads
    view.clear_bead()


def test_a_cleared_or_other_bead_is_drawn_anew(server):
    sim = _Sim()
    view = LiveView(server, sim)
    sim.publish(300)
    view._draw_bead()
    sim.publish(0)  # the next run clears the simulated bead
    view._draw_bead()
    assert _sent(view) == [] and view.bead_points_drawn == 0
    sim.publish(80, seed=1)
    view._draw_bead()
    sim.publish(200, seed=2)  # not the bead drawn (its deposits differ): all of it again
    view._draw_bead()
    assert _sent(view) == [200] and view.bead_points_drawn == 200


def test_a_new_plan_takes_the_bead_off_until_the_next_one(server):
    sim = _Sim()
    view = LiveView(server, sim)
    sim.publish(300)
    view._draw_bead()
    view.clear_bead()  # a new plan or part: the bead was laid for the one before
    view._draw_bead()  # the same message again: not drawn again
    assert _sent(view) == [] and view.bead_points_drawn == 0
    sim.publish(40, seed=3)  # the next run's bead
    view._draw_bead()
    assert _sent(view) == [40]
