"""tcp_pose_broadcaster: the pose of tool0 in the base frame, every control cycle, as a topic and on /tf."""
from __future__ import annotations

import numpy as np
from geometry_msgs.msg import PoseStamped, TransformStamped
from rclpy.node import Node
from tf2_msgs.msg import TFMessage

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.robot.sim_config import SimConfig


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
        base = f'{host.cfg.tf_prefix}base'
        pose = PoseStamped()
        pose.header.frame_id = base
        axes = ('x', 'y', 'z'), ('x', 'y', 'z', 'w')
        # Both published as CDR bytes patched in place (cdr_template.py), the same 7 values each cycle.
        self._pose = CdrTemplate(pose, stamps=('header.stamp',), floats=(
            *(f'pose.position.{a}' for a in axes[0]), *(f'pose.orientation.{a}' for a in axes[1])), publisher=self._pub)
        self._pub_tf = node.create_publisher(TFMessage, '/tf', 100)
        tf = TransformStamped(child_frame_id=f'{host.cfg.tf_prefix}tool0_controller')
        tf.header.frame_id = base
        self._tf = CdrTemplate(TFMessage(transforms=[tf]), stamps=('transforms[0].header.stamp',), floats=(
            *(f'transforms[0].transform.translation.{a}' for a in axes[0]),
            *(f'transforms[0].transform.rotation.{a}' for a in axes[1])), publisher=self._pub_tf)

    def update(self, cycle: Cycle) -> None:
        pose, tf = self._pose.listened(), self._tf.listened()
        if not (pose or tf):
            return
        values = np.concatenate((cycle.tcp_position, cycle.tcp_orientation))
        if pose:
            self._pose.publish(values, cycle.stamp_parts)
        if tf:
            self._tf.publish(values, cycle.stamp_parts)
