"""gravity_update_controller (ur_controllers/GravityUpdateController): the gravity of the robot's own model.

``~/set_gravity`` (ur_msgs/SetGravity): the direction and size of gravity (towards the earth) in any frame of the
robot. As upstream (``gravity_update_controller.cpp``): refused while the controller is not active ("Controller is
not active"); the vector is rotated into ``<tf_prefix>base`` (a frame the robot does not have is refused, naming
the frames), negated and sent to the robot's ``set_gravity``, which takes the acceleration away from the earth.

On the robot that vector is what its controller's dynamic model believes; the physical gravity does not change.
ur_sim does the same (``Simulator.set_gravity``): the controller compensates the believed gravity, so a vector
that does not match how the robot is mounted leaves gravity torques uncompensated, which the joint controller's
feedback takes up with a position error, and which pulls a robot in freedrive. ``ur_sim`` starts with the true
gravity, as a correctly installed robot.
"""
from __future__ import annotations

import numpy as np
from rclpy.node import Node
from ur_msgs.srv import SetGravity

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.ur_hardware import gravity_interfaces
from ur_sim_driver.description.frames import frame_rotations, rotation_between
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import kinematic_tree
from ur_sim_driver.robot.sim_config import SimConfig

NOT_ACTIVE = 'Controller is not active'
SET = 'Gravity has been set successfully'


class GravityUpdateController(Component):
    """Sets the gravity vector of the robot's dynamic model."""

    name = 'gravity_update_controller'
    type_name = 'ur_controllers/GravityUpdateController'

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return gravity_interfaces(cfg.tf_prefix), ()

    def on_configure(self, host: Host, node: Node) -> None:
        self._tree = kinematic_tree(host.sim.params, host.cfg.tf_prefix, get_tool(host.cfg.tool))
        self._base = f'{host.cfg.tf_prefix}base'
        # The driver's TCP frame (tcp_pose_broadcaster's); ur_sim's TCP is tool0.
        self._aliases = {f'{host.cfg.tf_prefix}tool0_controller': f'{host.cfg.tf_prefix}tool0'}
        node.create_service(SetGravity, '~/set_gravity', self._on_set)

    def _on_set(self, request: SetGravity.Request, response: SetGravity.Response) -> SetGravity.Response:
        logger = self.node.get_logger()
        response.success = False
        if not self.active:
            response.status = NOT_ACTIVE
            return response
        v = request.gravity.vector
        gravity = np.array([v.x, v.y, v.z], dtype=float)
        frame = request.gravity.header.frame_id
        if not np.all(np.isfinite(gravity)):
            response.status = f'gravity.vector = {gravity.tolist()} must be finite [m/s^2]'
            return response
        with self.host.lock:
            rotations = frame_rotations(self._tree, self.host.sim.state().q)
            try:
                rotation = rotation_between(rotations, self._base, self._aliases.get(frame, frame))
            except KeyError as exc:
                response.status = f'gravity.header.frame_id: {exc.args[0]}'
                logger.error(response.status)
                return response
            # The robot takes the acceleration away from the earth, in its base frame.
            self.host.sim.set_gravity(rotation @ -gravity)
        response.success, response.status = True, SET
        logger.info(SET)
        return response
