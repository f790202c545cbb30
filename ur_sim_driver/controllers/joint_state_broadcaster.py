"""joint_state_broadcaster: /joint_states every control cycle."""
from __future__ import annotations

import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import JointState

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.controllers.ur_hardware import joint_interfaces, prefixed_joints
from ur_sim_driver.robot.sim_config import SimConfig


class JointStateBroadcaster(Component):
    """Positions [rad], velocities [rad/s] and efforts [N m] of the arm joints, stamped with simulated time."""

    name = 'joint_state_broadcaster'
    type_name = 'joint_state_broadcaster/JointStateBroadcaster'

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return (), joint_interfaces(prefixed_joints(cfg.joints, cfg.tf_prefix), 'position', 'velocity', 'effort')

    def on_configure(self, host: Host, node: Node) -> None:
        # Upstream publishes on the node-relative 'joint_states', remapped to /joint_states by the launch file.
        self._pub = node.create_publisher(JointState, host.cfg.prefixed('joint_states'), 10)
        n = len(host.sim.joint_names)
        # Published as CDR bytes patched in place (cdr_template.py): a message object costs ~25 us a publish.
        self._cdr = CdrTemplate(JointState(name=list(host.sim.joint_names), position=[0.0] * n, velocity=[0.0] * n,
                                           effort=[0.0] * n),
                                stamps=('header.stamp',), floats=('position', 'velocity', 'effort'),
                                publisher=self._pub)

    def update(self, cycle: Cycle) -> None:
        if not self._cdr.listened():
            return
        state = cycle.state
        self._cdr.publish(np.concatenate((state.q, state.qd, state.effort)), cycle.stamp_parts)
