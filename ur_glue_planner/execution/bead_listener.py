"""The simulated bead from ur_sim: ``/ur_sim/glue_bead`` (sensor_msgs/PointCloud2) and ``/ur_sim/clear_glue_bead``.

Simulation only: a real UR driver has neither, and the planner then reports no bead (``available`` is False).
The cloud holds the whole bead so far (transient local): per deposit point x, y, z, width, height (float32, m)
and t (float64, simulated seconds), in the robot's ``base`` frame, which the planner's world (``base_link``,
the robot at the origin) sees rotated by pi about z. The message format is ``ur_sim_driver.description.bead``'s (a
message helper, not the simulator).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import PointCloud2
from std_srvs.srv import Trigger

from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.service_call import call_idempotent
from ur_sim_driver.description.bead import BASE_IN_WORLD, from_cloud

BEAD_TOPIC = '/ur_sim/glue_bead'
CLEAR_SERVICE = '/ur_sim/clear_glue_bead'


@dataclass(frozen=True, eq=False)
class BeadPoints:
    """Deposit points in time order, planner world frame: points (N, 3) [m], widths, heights (N,) [m], times (N,)
    [s] of the robot's (simulated) clock."""

    points: np.ndarray
    widths: np.ndarray
    heights: np.ndarray
    times: np.ndarray

    def until(self, t: float) -> BeadPoints:
        """The bead as it was at time t [s]."""
        k = int(np.searchsorted(self.times, t, side='right'))
        return BeadPoints(self.points[:k], self.widths[:k], self.heights[:k], self.times[:k])


def bead_from_cloud(msg: PointCloud2) -> BeadPoints:
    """Read the bead cloud (``ur_sim_driver.description.bead``'s format) in time order, turned from ``base`` to
    ``base_link``."""
    bead = from_cloud(msg)
    pts = np.asarray(bead.points, dtype=float) @ BASE_IN_WORLD[:3, :3].T
    order = np.argsort(bead.times, kind='stable')
    return BeadPoints(pts[order], np.asarray(bead.widths, float)[order], np.asarray(bead.heights, float)[order],
                      np.asarray(bead.times, float)[order])


class BeadListener:
    """Keeps the newest bead cloud and clears the simulated bead on request."""

    def __init__(self, node: Node, namespace: str = '') -> None:
        """``namespace``: ur_sim's ('' or e.g. '/ur10'), which prefixes the bead topic and its clear service."""
        self._node = node
        ns = namespace.strip('/')
        self.topic = f'/{ns}{BEAD_TOPIC}' if ns else BEAD_TOPIC
        self.clear_service = f'/{ns}{CLEAR_SERVICE}' if ns else CLEAR_SERVICE
        self._msg: PointCloud2 | None = None
        self._count = 0
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(PointCloud2, self.topic, self._on_bead, latched)
        self.clear_client = node.create_client(Trigger, self.clear_service)

    def _on_bead(self, msg: PointCloud2) -> None:
        self._msg = msg
        self._count += 1

    @property
    def received(self) -> int:
        return self._count

    def available(self, timeout: float = 2.0) -> bool:
        """Whether the simulator's bead interfaces are there (ur_sim with a dispenser)."""
        return self.clear_client.wait_for_service(timeout_sec=timeout)

    def clear(self, timeout: float = 5.0) -> None:
        """Remove the bead laid so far (the next job starts on clean glass); sent again while unanswered
        (clearing twice does no harm; see service_call.py)."""
        answer = call_idempotent(self.clear_client, Trigger.Request(), 'clearing the bead', timeout)
        if not answer.success:
            raise ClientError(f'{self.clear_service}: {answer.message}')

    def bead(self) -> BeadPoints | None:
        """The newest bead received, or None."""
        return None if self._msg is None else bead_from_cloud(self._msg)

    def final(self, timeout: float = 10.0) -> BeadPoints:
        """The bead as the simulator holds it now, once the flow has ended.

        The newest message received so far may not be the newest published: the whole-bead cloud is large and
        can arrive after a later, small joint state. A new subscription is given the publisher's latched
        (newest) message, so this is the last bead published before the call, whatever the delivery delays. The
        subscription is a node of its own, spun here: destroying an entity while another thread's executor waits
        on it is not safe in rclpy. Raises ClientError when nothing arrives within ``timeout`` [s] of wall time
        (a hang guard).
        """
        got: list[PointCloud2] = []
        context = self._node.context
        node = Node(f'{self._node.get_name()}_final_bead', context=context)
        executor = SingleThreadedExecutor(context=context)
        try:
            latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            node.create_subscription(PointCloud2, self.topic, got.append, latched)
            executor.add_node(node)
            deadline = time.monotonic() + timeout
            while not got:
                left = deadline - time.monotonic()
                if left <= 0.0:
                    raise ClientError(f'no bead on {self.topic} within {timeout} s')
                executor.spin_once(timeout_sec=min(0.1, left))
        finally:
            executor.shutdown()
            node.destroy_node()
        return bead_from_cloud(got[0])
