"""Simulation only: push a link of the robot from a test or a script (a hand on the arm, a bump).

``/ur_sim/apply_wrench`` (geometry_msgs/WrenchStamped, within ur_sim's namespace; not a driver interface):

* ``header.frame_id``: the body to push, a link of the robot as the URDF names it (``wrist_3_link``,
  ``forearm_link``, with the tf_prefix where one is configured) or the tool's body;
* ``wrench``: force [N] and torque [N m] in the robot's base frame, acting at the body's centre of mass;
* ``header.stamp``: the time at which the push ends, on ur_sim's clock (its /clock); zero: it lasts until the
  next message for that body. A zero wrench removes the push at once.

The push acts on the physics from the next control cycle on, like any external force: the robot's servo resists
it (position control), freedrive yields to it, and the flange's force-torque sensor feels it where it acts on
the tool. A message naming an unknown body is refused with a log line naming the known ones.
"""
from __future__ import annotations

import mujoco
import numpy as np
from geometry_msgs.msg import WrenchStamped
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node

from ur_sim_driver.controllers.base import Component, Cycle, Host

TOPIC = 'ur_sim/apply_wrench'


class AppliedWrenches(Component):
    """``/ur_sim/apply_wrench``: simulation-only external pushes on the robot's bodies."""

    name = 'ur_sim_wrench'
    type_name = 'ur_sim/AppliedWrenches'
    is_controller = False

    def __init__(self) -> None:
        super().__init__()
        self._ends: dict[int, float] = {}  # body id -> simulated end time [s] of its push (under the lock)

    def on_configure(self, host: Host, node: Node) -> None:
        node.create_subscription(WrenchStamped, host.cfg.prefixed(TOPIC), self._on_wrench, 10,
                                 callback_group=MutuallyExclusiveCallbackGroup())

    def _on_wrench(self, msg: WrenchStamped) -> None:
        physics = self.host.sim.physics
        name = msg.header.frame_id
        body = physics.body_id(name) if name else None
        w = msg.wrench
        values = np.array([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z])
        log = self.node.get_logger()
        if body is None or body == 0:
            model = physics.model
            known = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(1, model.nbody)]
            log.error(f"refused: header.frame_id = '{name}' is not a body of the simulation; known: "
                      f"{', '.join(n for n in known if n)}")
            return
        if not np.all(np.isfinite(values)):
            log.error(f'refused: the wrench on {name} has a non-finite value: {values.tolist()}')
            return
        end = self.host.clock.sim_time(msg.header.stamp)
        with self.host.lock:
            physics.set_external_wrench(body, values[:3], values[3:])
            if values.any() and end > 0.0:
                self._ends[body] = end
            else:
                self._ends.pop(body, None)
        log.info(f'push on {name}: force {values[:3].tolist()} N, torque {values[3:].tolist()} N m'
                 + (f' until simulated t = {end:.3f} s' if values.any() and end > 0.0 else ''))

    def update(self, cycle: Cycle) -> None:
        if not self._ends:
            return
        with self.host.lock:
            now = self.host.sim.time
            for body, end in list(self._ends.items()):
                if now >= end:
                    self.host.sim.physics.set_external_wrench(body, np.zeros(3), np.zeros(3))
                    del self._ends[body]
