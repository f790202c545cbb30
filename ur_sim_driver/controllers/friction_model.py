"""friction_model_controller (ur_controllers/FrictionModelController): the friction compensation scales of the
robot's torque control.

``~/set_friction_model_parameters`` (ur_msgs/SetFrictionModelParameters): six viscous and six Coulomb scale factors,
one per joint. Facts from the driver (``friction_model_controller.cpp``) and its client library
(``ScriptCommandInterface::setFrictionScales``):

* refused while the controller is inactive ("Can't accept new requests. Controller is not running.");
* each list must have exactly 6 elements, else refused naming the list and its length;
* the robot's software must be 5.25.1 (PolyScope 5) or later, else the client library warns that the command has
  no effect and the answer is false; the External Control program must run (the scales go through its script
  command socket), else the answer is false too;
* the scales are clamped to [0, 1] and sent to the robot, where they scale the friction compensation of
  ``direct_torque`` (``Simulator.friction_scales``, ``robot/direct_torque.py``: the joints feel the friction the
  compensation leaves). The controller keeps the last ones (:attr:`FrictionModelController.scales`) and sends
  them again when it is activated again, as upstream does. They act only under torque control (the
  forward_effort_controller): in position, velocity and passthrough control they change nothing, as on the robot.

Its command interfaces (``<tf_prefix>friction_model/*``) start no robot mode: it runs beside every other controller.
"""
from __future__ import annotations

import numpy as np
from rclpy.node import Node
from ur_msgs.srv import SetFrictionModelParameters

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.ur_hardware import friction_interfaces
from ur_sim_driver.robot.direct_torque import FrictionScales
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.software import FRICTION_SCALES, supports

NOT_RUNNING = "Can't accept new requests. Controller is not running."


class FrictionModelController(Component):
    """The friction scales the robot's torque control would use."""

    name = 'friction_model_controller'
    type_name = 'ur_controllers/FrictionModelController'

    def __init__(self) -> None:
        super().__init__()
        self.scales: tuple[np.ndarray, np.ndarray] | None = None  # (viscous, Coulomb) last set on the robot

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return friction_interfaces(cfg.tf_prefix), ()

    def on_configure(self, host: Host, node: Node) -> None:
        node.create_service(SetFrictionModelParameters, '~/set_friction_model_parameters', self._on_set)

    def on_activate(self) -> None:
        if self.scales is not None and self.node is not None:
            self.node.get_logger().info('Restoring friction model parameters from before deactivation. If this is '
                                        'not desired, please set new parameters using the service.')
            if self.host.robot.program_running:  # under the lock: activation runs in the simulation loop
                self.host.sim.friction_scales = FrictionScales.make(*self.scales)

    def _on_set(self, request: SetFrictionModelParameters.Request,
                response: SetFrictionModelParameters.Response) -> SetFrictionModelParameters.Response:
        logger = self.node.get_logger()
        response.success = False
        viscous, coulomb = list(request.parameters.viscous_scale), list(request.parameters.coulomb_scale)
        version = self.host.cfg.software_version
        if not self.active:
            logger.error(NOT_RUNNING)
        elif len(viscous) != 6:
            logger.error(f'viscous_scale must have exactly 6 elements, got {len(viscous)}.')
        elif len(coulomb) != 6:
            logger.error(f'coulomb_scale must have exactly 6 elements, got {len(coulomb)}.')
        elif not supports(version, FRICTION_SCALES):
            five, x = FRICTION_SCALES
            logger.warning(f'setFrictionScales is only available for robots with PolyScope {five} / {x} or later. '
                           f"This robot's version is {version}. This command will have no effect.")
            logger.error('Could not set the friction model parameters.')
        elif not self.host.robot.program_running:  # the scales go through the program's script command socket
            logger.error('Script command interface is not running. Unable to set friction scales.')
            logger.error('Could not set the friction model parameters.')
        else:
            with self.host.lock:
                self.scales = (np.clip(viscous, 0.0, 1.0), np.clip(coulomb, 0.0, 1.0))
                self.host.sim.friction_scales = FrictionScales.make(*self.scales)
            response.success = True
            logger.info('Friction model parameters have been set successfully.')
        return response
