"""speed_scaling_state_broadcaster: the robot's speed scaling in percent, every control cycle."""
from __future__ import annotations

from rclpy.node import Node
from std_msgs.msg import Float64

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.robot.sim_config import SimConfig


class SpeedScalingStateBroadcaster(Component):
    """``~/speed_scaling`` (std_msgs/Float64): the robot's own factor x 100 (speed slider x its slowdowns)."""

    name = 'speed_scaling_state_broadcaster'
    type_name = 'ur_controllers/SpeedScalingStateBroadcaster'

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return (), (f'{cfg.tf_prefix}speed_scaling/speed_scaling_factor',)

    def on_configure(self, host: Host, node: Node) -> None:
        self._pub = node.create_publisher(Float64, host.cfg.prefixed(f'{self.name}/speed_scaling'), 10)
        # CDR bytes patched in place (cdr_template.py)
        self._cdr = CdrTemplate(Float64(), floats=('data',), publisher=self._pub)

    def update(self, cycle: Cycle) -> None:
        if self._cdr.listened():
            self._cdr.publish((cycle.robot_factor * 100.0,))
