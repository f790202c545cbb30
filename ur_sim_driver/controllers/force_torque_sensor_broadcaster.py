"""force_torque_sensor_broadcaster: the flange's force-torque sensor, every control cycle."""
from __future__ import annotations

from geometry_msgs.msg import WrenchStamped
from rclpy.node import Node

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate


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
        msg = WrenchStamped()
        msg.header.frame_id = f'{host.cfg.tf_prefix}tool0_controller'
        # Published as CDR bytes patched in place (cdr_template.py).
        self._cdr = CdrTemplate(msg, stamps=('header.stamp',),
                                floats=tuple(f'wrench.{v}.{a}' for v in ('force', 'torque') for a in 'xyz'),
                                publisher=self._pub)

    def update(self, cycle: Cycle) -> None:
        if self._cdr.listened():
            self._cdr.publish(cycle.wrench, cycle.stamp_parts)
