"""ur_configuration_controller (ur_controllers/URConfigurationController): the robot's software version.

``~/get_robot_software_version`` (ur_msgs/GetRobotSoftwareVersion) answers the PolyScope version of the
simulated controller: major 5 for an e-series robot (``ur5e``, ``ur10e``), 3 for a CB3 (``ur5``, ``ur10``),
as a real robot of that type reports it. The minor and bugfix numbers are those of widely used releases
(5.12.6, the URSim e-series image many driver users test with; 3.15.8, a late CB3 release). UR's build
numbers are not published with the version, so build is 0: it marks the version as a simulated one.
"""
from __future__ import annotations

from typing import NamedTuple

from rclpy.node import Node
from ur_msgs.srv import GetRobotSoftwareVersion

from ur_sim_driver.controllers.base import Component, Host


class SoftwareVersion(NamedTuple):
    major: int
    minor: int
    bugfix: int
    build: int


E_SERIES_VERSION = SoftwareVersion(5, 12, 6, 0)
CB3_VERSION = SoftwareVersion(3, 15, 8, 0)


def software_version(ur_type: str) -> SoftwareVersion:
    """The version a robot of `ur_type` reports (e-series types end in 'e')."""
    return E_SERIES_VERSION if ur_type.endswith('e') else CB3_VERSION


class UrConfigurationController(Component):
    """Answers what the robot's controller is; the answer does not change while ur_sim runs."""

    name = 'ur_configuration_controller'
    type_name = 'ur_controllers/URConfigurationController'

    def on_configure(self, host: Host, node: Node) -> None:
        self._version = software_version(host.cfg.ur_type)
        node.create_service(GetRobotSoftwareVersion, host.cfg.prefixed(f'{self.name}/get_robot_software_version'),
                            self._on_get_version)

    def _on_get_version(self, req: GetRobotSoftwareVersion.Request,
                        res: GetRobotSoftwareVersion.Response) -> GetRobotSoftwareVersion.Response:
        res.major, res.minor, res.bugfix, res.build = self._version
        return res
