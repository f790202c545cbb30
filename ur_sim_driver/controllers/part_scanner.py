"""Simulation only: the cell's laser profile scanners measuring the part (a scene with a ``scanners:`` block).

Glue cells measure each part before dispensing (the glass comes in a little off); the driver has no interface for
that, a scanner has its own driver. In the simulation this component is those scanners and their driver:

* at configure it casts every scanner's beams onto the scene bodies the scanners target
  (``ur_sim_driver/physics/ray_scan.py``, MuJoCo ray casting on the parts' meshes);
* every ``1 / rate`` [s] of simulated time it publishes a measurement on ``/ur_sim/part_scan``
  (sensor_msgs/PointCloud2, organised: one row per scanner, one column per beam, x, y, z float32 [m] in
  ``<tf_prefix>base_link``, NaN where a beam saw nothing within range; ``description/part_scan.py``), each
  range with fresh noise of the setup's ``noise`` [m, 1 sigma] along its beam, transient local (a late reader
  gets the newest at once). The noise comes from a generator seeded by ``part_scan_seed`` (reproducible runs).

With no scanners in the scene, nothing of it exists.
"""
from __future__ import annotations

import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import PointCloud2

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.description.part_scan import to_cloud
from ur_sim_driver.physics.ray_scan import PartRays, measure

TOPIC = 'ur_sim/part_scan'


class PartScanners(Component):
    """The scene's part scanners and their cloud; only in a scene that has scanners."""

    name = 'ur_sim_part_scanners'
    type_name = 'ur_sim/PartScanners'
    is_controller = False  # simulation only: the controller manager does not list or switch it

    def configure(self, host: Host) -> None:
        self.host = host
        if host.sim.scanners is None:
            return
        super().configure(host)

    def activate(self) -> None:
        if self.node is not None:
            super().activate()

    def on_configure(self, host: Host, node: Node) -> None:
        cfg, setup = host.cfg, host.sim.scanners
        self.setup = setup
        targets = [(name, mesh, pose) for name, mesh, pose, _ in host.sim.scene_bodies if name in setup.targets]
        rays = PartRays(targets)
        self._profiles = [rays.profile(unit, setup.max_range) for unit in setup.units]
        self._origins = [np.asarray(unit.origin) for unit in setup.units]
        world_to_base_link = np.linalg.inv(host.sim.base_link_in_world)
        self._r, self._p = world_to_base_link[:3, :3], world_to_base_link[:3, 3]
        self._rng = np.random.default_rng(cfg.part_scan_seed)
        self._period = 1.0 / setup.rate
        self._next = 0.0
        self.frame_id = cfg.tf_prefix + 'base_link'
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self._pub = node.create_publisher(PointCloud2, cfg.prefixed(TOPIC), latched)
        seen = ', '.join(f'{u.name} {int(np.isfinite(r).sum())}/{u.points}'
                         for u, (_, r) in zip(setup.units, self._profiles))
        node.get_logger().info(f'{len(setup.units)} part scanners on {cfg.prefixed(TOPIC)} every '
                               f'{self._period:.2f} s, noise {setup.noise * 1e3:.3f} mm; beams on the part: {seen}')

    def measurement(self) -> np.ndarray:
        """One measurement: points (scanners, beams, 3) [m] in base_link, NaN where a beam saw nothing."""
        rows = [measure(o, beams, ranges, self.setup.noise, self._rng)
                for o, (beams, ranges) in zip(self._origins, self._profiles)]
        return np.stack(rows) @ self._r.T + self._p

    def update(self, cycle: Cycle) -> None:
        if cycle.t < self._next:
            return
        self._next = cycle.t + self._period
        self._pub.publish(to_cloud(self.measurement(), self.frame_id, cycle.stamp))
