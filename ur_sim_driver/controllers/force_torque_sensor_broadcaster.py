"""force_torque_sensor_broadcaster: the flange's force-torque sensor, every control cycle."""
from __future__ import annotations

from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node

from ur_sim_driver.controllers.base import Component, Cycle, Host


class ForceTorqueSensorBroadcaster(Component):
    """``~/wrench`` (geometry_msgs/WrenchStamped) in ``<tf_prefix>tool0_controller``.

    As the driver reports it: the TCP force and torque in the tool frame's axes about the TCP (tool0 here),
    i.e. what the tool, the payload and their contacts exert on the arm, less the zero set by
    zero_ftsensor. Read under the simulation lock in the node's cycle (``Cycle.wrench``).
    """

    name = 'force_torque_sensor_broadcaster'
    type_name = 'force_torque_sensor_broadcaster/ForceTorqueSensorBroadcaster'

    def on_configure(self, host: Host, node: Node) -> None:
        self._pub = node.create_publisher(WrenchStamped, host.cfg.prefixed(f'{self.name}/wrench'), 10)
        self._msg = WrenchStamped()
        self._msg.header.frame_id = f'{host.cfg.tf_prefix}tool0_controller'

    def update(self, cycle: Cycle) -> None:
        msg = self._msg
        msg.header.stamp = cycle.stamp
        f, t = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z, t.x, t.y, t.z = cycle.wrench.tolist()
        self._pub.publish(msg)
