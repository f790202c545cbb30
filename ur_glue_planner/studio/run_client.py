"""The studio's connection for running jobs: one client for every run, and a steady wait before the bead.

Each Run used to make a new :class:`~ur_glue_planner.execution.client.URClient` (a new node named
``ur_glue_studio_client``, its subscriptions and action client, discovered anew) and close it afterwards. Its bead
start was stamped ahead by ``delivery_margin``: 4 x the slowest goal answer seen *by that client*, scaled up by the
ratio of points. A new client had seen only the run's own approach (201 points) and descent (95 points); their
answers vary from 7 to 180 ms in the studio's busy process (page loop, browser, simulation), and scaled to the
bead's 792 points that became a wait of 1 to 6 s, different every run; beyond 5 s ur_sim warned that the client's
clock was wrong.

Here one client serves every run (no node made per run), and the bead's margin comes from the answers to earlier
beads when there are any: a measured delivery of a goal that long, not one extrapolated 8-fold from a short goal.
The first run after connecting has none and extrapolates as the planner does.

An earlier bead counts when it had at least ``BEAD_SHARE`` of the new bead's points, its answer scaled up by the
ratio: a bead planned on a measured part is a little longer or shorter than the one before, so it has a few
points more or fewer; when only beads of at least as many points counted, a longer one found no earlier bead and
its wait went back to the short goals' extrapolation (issue 44: 1.1 s -> 5.7 s on a measured part).
"""
from __future__ import annotations

from collections.abc import Sequence

from ur_glue_planner.execution.bead_listener import BeadListener
from ur_glue_planner.execution.client import URClient, delivery_margin
from ur_glue_planner.execution.dispenser_io import DispenserIO, dispenser_for

RECENT = 5  # answers of earlier beads that set the margin (the newest)
BEAD_SHARE = 0.5  # an earlier goal of at least this share of the bead's points is a bead (approach 201, bead 792)
NODE_NAME = 'ur_glue_studio_client'


def bead_margin(answers: Sequence[tuple[float, int]], delivery: float, points: int) -> float:
    """Wall time [s] allowed for a goal of ``points`` points to reach the controller.

    ``answers``: (seconds, points) of the goals sent before, oldest first. The RECENT newest of at least
    ``BEAD_SHARE`` x ``points`` points decide when there are any (``delivery_margin`` of them, each scaled to
    ``points`` when shorter: at most 1 / BEAD_SHARE-fold); else ``delivery_margin`` of all.
    """
    same = [a for a in answers if a[1] >= BEAD_SHARE * points][-RECENT:]
    return delivery_margin(same if same else answers, delivery, points)


class StudioClient(URClient):
    """A URClient kept for every run of the studio, with the glue gun and the bead listener on its node."""

    def __init__(self, namespace: str, controller_name: str, timeout: float, context) -> None:
        super().__init__(namespace=namespace, controller_name=controller_name, timeout=timeout, context=context,
                         node_name=NODE_NAME)
        self.key = (namespace, controller_name)
        self.runs = 0  # runs started on this client
        # Made once with the node: entities made per run would pile up on it (destroying them under the
        # spinning executor is not safe in rclpy).
        self.gun: DispenserIO = dispenser_for(self.node, self.prefix, controller_name)
        self.bead = BeadListener(self.node, self.prefix)

    def start_time(self, lead: float = 0.1, delivery: float = 0.3, points: int = 1) -> float:
        """As URClient's, with :func:`bead_margin` for the delivery."""
        return self.now() + lead + bead_margin(self.goal_answers, delivery, points) * self.time_rate()
