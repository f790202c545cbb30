"""tcp_pose_broadcaster: the pose of tool0 in the base frame, every control cycle."""
from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from rclpy.node import Node

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.sim_config import SimConfig


class TcpPoseBroadcaster(Component):
    """``~/pose`` (geometry_msgs/PoseStamped) in ``<tf_prefix>base``."""

    name = 'tcp_pose_broadcaster'
    type_name = 'pose_broadcaster/PoseBroadcaster'

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        axes = ('position.x', 'position.y', 'position.z', 'orientation.x', 'orientation.y', 'orientation.z',
                'orientation.w')
        return (), tuple(f'{cfg.tf_prefix}tcp_pose/{a}' for a in axes)

    def on_configure(self, host: Host, node: Node) -> None:
        self._pub = node.create_publisher(PoseStamped, host.cfg.prefixed(f'{self.name}/pose'), 10)
        self._msg = PoseStamped()
        self._msg.header.frame_id = f'{host.cfg.tf_prefix}base'

    def update(self, cycle: Cycle) -> None:
        msg = self._msg
        msg.header.stamp = cycle.stamp
        p = msg.pose.position
        p.x, p.y, p.z = cycle.tcp_position.tolist()
        o = msg.pose.orientation
        o.x, o.y, o.z, o.w = cycle.tcp_orientation.tolist()
        self._pub.publish(msg)
