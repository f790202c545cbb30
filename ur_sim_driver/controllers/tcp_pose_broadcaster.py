"""tcp_pose_broadcaster: the pose of tool0 in the base frame, every control cycle, as a topic and on /tf."""
from __future__ import annotations

from geometry_msgs.msg import PoseStamped, TransformStamped
from rclpy.node import Node
from tf2_msgs.msg import TFMessage

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.sim_config import SimConfig


class TcpPoseBroadcaster(Component):
    """``~/pose`` (geometry_msgs/PoseStamped) in ``<tf_prefix>base``, and ``<tf_prefix>base`` ->
    ``<tf_prefix>tool0_controller`` on /tf (the driver's TCP frame; ur_sim's TCP is tool0)."""

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
        self._pub_tf = node.create_publisher(TFMessage, '/tf', 100)
        tf = TransformStamped(child_frame_id=f'{host.cfg.tf_prefix}tool0_controller')
        tf.header.frame_id = self._msg.header.frame_id
        self._tf_msg = TFMessage(transforms=[tf])
        self._tf = self._tf_msg.transforms[0]

    def update(self, cycle: Cycle) -> None:
        msg = self._msg
        msg.header.stamp = cycle.stamp
        x, y, z = cycle.tcp_position.tolist()
        qx, qy, qz, qw = cycle.tcp_orientation.tolist()
        p, o = msg.pose.position, msg.pose.orientation
        p.x, p.y, p.z = x, y, z
        o.x, o.y, o.z, o.w = qx, qy, qz, qw
        self._pub.publish(msg)
        tf = self._tf
        tf.header.stamp = cycle.stamp
        t, r = tf.transform.translation, tf.transform.rotation
        t.x, t.y, t.z = x, y, z
        r.x, r.y, r.z, r.w = qx, qy, qz, qw
        self._pub_tf.publish(self._tf_msg)
