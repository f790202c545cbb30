"""joint_state_broadcaster: /joint_states every control cycle."""
from __future__ import annotations

from rclpy.node import Node
from sensor_msgs.msg import JointState

from ur_sim_driver import conversions as conv
from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.sim_config import SimConfig
from ur_sim_driver.ur_hardware import joint_interfaces, prefixed_joints


class JointStateBroadcaster(Component):
    """Positions [rad], velocities [rad/s] and efforts [N m] of the arm joints, stamped with simulated time."""

    name = 'joint_state_broadcaster'
    type_name = 'joint_state_broadcaster/JointStateBroadcaster'

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return (), joint_interfaces(prefixed_joints(cfg.joints, cfg.tf_prefix), 'position', 'velocity', 'effort')

    def on_configure(self, host: Host, node: Node) -> None:
        # Upstream publishes on the node-relative 'joint_states', remapped to /joint_states by the launch file.
        self._pub = node.create_publisher(JointState, host.cfg.prefixed('joint_states'), 10)
        self._msg = JointState(name=list(host.sim.joint_names))

    def update(self, cycle: Cycle) -> None:
        msg = self._msg
        msg.header.stamp = cycle.stamp
        msg.position = conv.float_array(cycle.state.q)
        msg.velocity = conv.float_array(cycle.state.qd)
        msg.effort = conv.float_array(cycle.state.effort)
        self._pub.publish(msg)
