"""ur_configuration_controller (ur_controllers/URConfigurationController): the robot's software version.

``~/get_robot_software_version`` (ur_msgs/GetRobotSoftwareVersion) answers the software version of the simulated
controller (parameter ``software_version``; by default 5.25.1 for an e-series type, 3.15.8 for a CB3: see
``robot/software.py``), as a real robot reports it.
"""
from __future__ import annotations

from rclpy.node import Node
from ur_msgs.srv import GetRobotSoftwareVersion

from ur_sim_driver.controllers.base import Component, Host


class UrConfigurationController(Component):
    """Answers what the robot's controller is; the answer does not change while ur_sim runs."""

    name = 'ur_configuration_controller'
    type_name = 'ur_controllers/URConfigurationController'

    def on_configure(self, host: Host, node: Node) -> None:
        self._version = host.cfg.software_version
        node.create_service(GetRobotSoftwareVersion, host.cfg.prefixed(f'{self.name}/get_robot_software_version'),
                            self._on_get_version)

    def _on_get_version(self, req: GetRobotSoftwareVersion.Request,
                        res: GetRobotSoftwareVersion.Response) -> GetRobotSoftwareVersion.Response:
        res.major, res.minor, res.bugfix, res.build = self._version
        return res
