"""Simulation only: the glue dispenser on a digital output and the bead it lays on the scene (``tool: dispenser``).

A real gun is wired to an output and the glass shows the result; the driver has no interface for either. In
the simulation this component is that gun and glass (model: ``ur_sim_driver/robot/dispenser.py``):

* every control cycle it reads ``Simulator.io``'s digital output ``dispenser.pin`` (set through the driver's
  ``/io_and_status_controller/set_io``) and advances the flow;
* while material flows it casts the nozzle axis (tool0's z, from the tip ``dispenser_tip``) onto the scene
  with ``mj_ray`` (the dispenser body excluded; a hit on the robot counts as material lost) and adds the
  cycle's volume to the bead where the axis meets the nearest surface within ``MAX_STANDOFF`` of the tip;
* it publishes the whole bead so far on ``/ur_sim/glue_bead`` (sensor_msgs/PointCloud2, frame
  ``<tf_prefix>base``, fields x, y, z, width, height float32 [m], t float64 [s]: ``ur_sim_driver/robot/bead.py``),
  transient local, every ``PUBLISH_PERIOD`` of simulated time (at most every ``MIN_WALL_PERIOD`` of wall
  time, so that a fast simulation does not flood it), on every change of the output and when the flow has
  stopped;
* ``/ur_sim/clear_glue_bead`` (std_srvs/Trigger) removes the bead (a new part).

While the output is off and the flow has died away it does nothing but read one output per cycle.
"""
from __future__ import annotations

import threading
import time

import mujoco
import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import PointCloud2
from std_srvs.srv import Trigger

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.description.bead import Bead, to_cloud
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.robot.dispenser import MAX_STANDOFF, BeadTrack, FlowState, flow_step

PUBLISH_PERIOD = 0.1  # [s] of simulated time between bead messages while it grows
MIN_WALL_PERIOD = 0.05  # [s] of wall time between periodic bead messages
# The ray starts this far behind the tip, inside the nozzle's last 10 mm (which have no collision shape), so that
# a tip touching or slightly pressed into the glass still finds its surface.
RAY_BACKSET = 0.01  # [m]
_ML = 1e6  # [ml] per [m^3]


class SimulatedDispenser(Component):
    """The dispenser tool's gun and the bead on the scene; only with ``tool: dispenser``."""

    name = 'ur_sim_dispenser'
    type_name = 'ur_sim/SimulatedDispenser'
    is_controller = False  # simulation only: the controller manager does not list or switch it

    def configure(self, host: Host) -> None:
        self.host = host
        if host.cfg.tool != 'dispenser':
            return  # no dispenser, no node: nothing of it exists
        super().configure(host)

    def activate(self) -> None:
        if self.node is not None:  # stays inactive (not updated) without a dispenser
            super().activate()

    def on_configure(self, host: Host, node: Node) -> None:
        cfg, tool = host.cfg, get_tool(host.cfg.tool)
        self.params = cfg.dispenser
        self.frame_id = cfg.tf_prefix + 'base'
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self._pub = node.create_publisher(PointCloud2, cfg.prefixed('ur_sim/glue_bead'), latched)
        node.create_service(Trigger, cfg.prefixed('ur_sim/clear_glue_bead'), self._on_clear)
        physics = host.sim.physics
        m = physics.model
        self._model, self._data = m, physics.data
        self._tool_body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, cfg.tf_prefix + tool.name)
        base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, cfg.tf_prefix + 'base')
        self._robot_geom = m.body_rootid[m.geom_bodyid] == m.body_rootid[base]
        with host.lock:  # the base is fixed in the world: its pose once
            self._world_r = physics.data.xmat[base].reshape(3, 3).copy()
            self._world_p = physics.data.xpos[base].copy()
        self._tip = tool.tip_in_tool0()[:3, 3].copy()  # [m] in tool0; the nozzle axis is tool0's z
        self._geomid = np.zeros(1, dtype=np.int32)
        self._state = FlowState()
        self._track = BeadTrack(self.params.nozzle)
        self._lock = threading.Lock()  # the track: the loop adds, the clear service replaces it
        self._published_len = -1
        self._next_sim = 0.0
        self._next_wall = 0.0
        self._lost_warned = False
        node.get_logger().info(
            f'dispenser on digital output {self.params.pin}: {self.params.flow_rate} ml/s, nozzle '
            f'{self.params.nozzle_diameter} mm, delays {self.params.on_delay}/{self.params.off_delay} s, '
            f'time constant {self.params.time_constant} s; bead on {cfg.prefixed("ur_sim/glue_bead")}')

    # ---- the cycle (simulation thread) ---------------------------------------------------------------
    def update(self, cycle: Cycle) -> None:
        output = self.host.sim.io.digital_out[self.params.pin]
        state = self._state
        if state.idle and not output:
            return
        changed = output != state.output
        self._state, volume = flow_step(self.params, state, cycle.t, output)
        point = self._surface_point(cycle)
        with self._lock:
            self._track.add(cycle.t, point, volume)
            if self._state.idle:
                self._track.end_run()
            lost = self._track.lost
        if lost > 0.0 and not self._lost_warned:
            self._lost_warned = True
            self.node.get_logger().warning(f'glue lost: no surface within {MAX_STANDOFF * 1e3:.0f} mm of the '
                                           'nozzle along its axis')
        if changed or self._state.idle or (cycle.t >= self._next_sim and time.monotonic() >= self._next_wall):
            self._publish(cycle, force=changed)
        if self._state.idle:
            with self._lock:
                deposited, lost = self._track.deposited, self._track.lost
            self.node.get_logger().info(f'dispenser stopped: {deposited * _ML:.3f} ml on the bead, '
                                        f'{lost * _ML:.3f} ml lost')

    def _surface_point(self, cycle: Cycle) -> np.ndarray | None:
        """Where the nozzle axis meets the nearest scene surface within reach, in the base frame, or None; from the
        TCP pose of the cycle's state (its time is the cycle's)."""
        r = Rotation.from_quat(cycle.tcp_orientation).as_matrix()  # (x, y, z, w), as SciPy orders it
        axis_base = r[:, 2]
        tip_base = cycle.tcp_position + r @ self._tip
        start = self._world_r @ (tip_base - RAY_BACKSET * axis_base) + self._world_p
        axis = self._world_r @ axis_base
        with self.host.lock:  # a service may be recomputing the data (set_payload)
            dist = mujoco.mj_ray(self._model, self._data, start, axis, None, 1, self._tool_body, self._geomid)
        if dist < 0.0 or dist > RAY_BACKSET + MAX_STANDOFF or self._robot_geom[self._geomid[0]]:
            return None
        return tip_base + (dist - RAY_BACKSET) * axis_base

    def _publish(self, cycle: Cycle, force: bool = False) -> None:
        # A message on every output change, stamped with the cycle that saw it, even if the bead is unchanged.
        with self._lock:
            n = len(self._track)
            if n == self._published_len and not force:
                return
            bead = self._track.bead()
        self._pub.publish(to_cloud(bead, self.frame_id, cycle.stamp, self.host.clock.origin_ns * 1e-9))
        self._published_len = n
        self._next_sim = cycle.t + PUBLISH_PERIOD
        self._next_wall = time.monotonic() + MIN_WALL_PERIOD

    # ---- service (executor thread) ---------------------------------------------------------------------
    def _on_clear(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        with self._lock:
            old = self._track
            self._track = BeadTrack(self.params.nozzle)
            self._published_len = 0
            self._lost_warned = False
        msg = to_cloud(Bead.empty(), self.frame_id, self.host.clock.stamp(self.host.sim.time))
        self._pub.publish(msg)
        res.success = True
        res.message = (f'glue bead cleared ({len(old.bead())} points, {old.deposited * _ML:.3f} ml deposited, '
                       f'{old.lost * _ML:.3f} ml lost)')
        self.node.get_logger().info(res.message)
        return res
