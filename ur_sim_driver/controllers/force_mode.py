"""force_mode_controller (ur_controllers/ForceModeController): ``~/start_force_mode`` (ur_msgs/SetForceMode) and
``~/stop_force_mode`` (std_srvs/Trigger).

Upstream (``force_mode_controller.cpp`` at the pinned commit): the services exist while the controller is loaded;
a start is refused while the controller is inactive, for an all-zero quaternion, for a task frame that does not
transform to ``<tf_prefix>base`` (transformed once, at the request), a type outside 1..3, a damping outside [0, 1]
and a gain scaling outside [0, 2] (above 1 only a warning), each with upstream's log text and ``success`` false. A
compliant axis takes its speed limit, another its deviation limit. A start while force mode runs replaces its
parameters. Deactivating the controller (a switch, or the robot's program stopping) ends force mode; activating it
again does not restart it. The controller claims ``<tf_prefix>force_mode/...``, which runs alone or beside the
passthrough trajectory controller only (``ur_hardware.py``).

The robot's side is ``motion/force_mode.py``: each cycle the compliant axes' velocity follows from the wrench the
robot applies (the flange's force-torque reading, negated) and becomes an offset of the active controller's joint
reference (through the tool's Jacobian), so the other axes follow the program. When force mode ends the robot
holds where it left the reference. Each cycle the TCP (tool0) as measured is compared with where the last cycle's
reference puts it: a non-compliant axis of the force frame deviating further than its deviation limit is the
robot's protective stop (``RobotState.protective_stop``, its cause naming the axis, the deviation and the limit;
logged as the simulation loop logs a contact's). Force mode ends with it and the robot holds where it stopped; the
driver's controller_stopper then deactivates the controller, and activates it again once the stop is unlocked,
without force mode. CB3 robots ignore the gain scaling, with upstream's warning.
"""
from __future__ import annotations

import numpy as np
from rclpy.node import Node
from scipy.spatial.transform import Rotation
from std_srvs.srv import Trigger
from ur_msgs.srv import SetForceMode

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.ur_hardware import FORCE_MODE
from ur_sim_driver.description.analytic_ik import UrAnalyticIK
from ur_sim_driver.description.frames import frame_poses, pose_between
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import kinematic_tree
from ur_sim_driver.motion.force_mode import ForceModeSpec, admittance_step, deviation, deviation_cause, force_frame
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.urscript.moves import tool_jacobian

NAME = 'force_mode_controller'
TYPE = 'ur_controllers/ForceModeController'
AXES = ('x', 'y', 'z', 'rx', 'ry', 'rz')
_DH_FROM_BASE = np.diag([-1.0, -1.0, 1.0, 1.0])  # the controller's base frame is DH frame 0
_SINGULAR = 1e-3  # damping of the Jacobian's inverse near a singularity
# Upstream's log lines.
INACTIVE = "Can't accept new requests. Controller is not running."
ZERO_QUATERNION = 'Received task frame with all-zeros quaternion. It should have at least one non-zero entry.'
SET = 'Force mode has been set successfully.'
DISABLED = 'Force mode has been disabled successfully.'
CB3_GAIN = 'Force mode gain scaling cannot be used on CB3 robots. Starting force mode, but disregarding gain scaling.'


class ForceModeController(Component):
    """The driver's force_mode_controller and the robot's force mode.

    Attributes:
        spec: the force mode running (None: none), read by the simulation loop under the lock.
    """

    name = NAME
    type_name = TYPE
    initially_active = False

    def __init__(self) -> None:
        super().__init__()
        self.spec: ForceModeSpec | None = None
        self._velocity = np.zeros(6)  # the compliant axes' velocity, force frame [m/s, rad/s]
        self._offset: np.ndarray | None = None  # (n,) the joint offset force mode adds to the reference [rad]
        self._hold: np.ndarray | None = None  # where the robot holds once force mode has ended [rad]
        self._target: np.ndarray | None = None  # (4, 4) the TCP's pose in base by the last cycle's reference
        self._halt = False  # a deviation stopped the robot: it holds where it is from the next cycle on
        self._stop_cause: str | None = None  # that stop's cause, logged outside the lock

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        p = f'{cfg.tf_prefix}{FORCE_MODE}/'
        names = [*(f'task_frame_{a}' for a in AXES), *(f'selection_vector_{a}' for a in AXES),
                 *(f'wrench_{a}' for a in AXES), 'type', *(f'limits_{a}' for a in AXES), 'force_mode_async_success',
                 'disable_cmd', 'damping', 'gain_scaling']
        return tuple(p + n for n in names), (f'{cfg.tf_prefix}system_interface/initialized',)

    def on_configure(self, host: Host, node: Node) -> None:
        self._tree = kinematic_tree(host.sim.params, host.cfg.tf_prefix, get_tool(host.cfg.tool))
        self._base = f'{host.cfg.tf_prefix}base'
        self._aliases = {f'{host.cfg.tf_prefix}tool0_controller': f'{host.cfg.tf_prefix}tool0'}
        self._ik = UrAnalyticIK(host.sim.params.dh, base_pose=_DH_FROM_BASE)
        self._cb3 = host.sim.params.series == 'cb3'
        node.create_service(SetForceMode, '~/start_force_mode', self._on_start)
        node.create_service(Trigger, '~/stop_force_mode', self._on_stop)

    def on_deactivate(self) -> None:  # the controller manager switches in the simulation loop, under the lock
        self._end()

    # ---- services (executor threads) --------------------------------------------------------------------------
    def _on_start(self, request: SetForceMode.Request, response: SetForceMode.Response) -> SetForceMode.Response:
        logger = self.node.get_logger()
        response.success = False
        frame = request.task_frame
        o = frame.pose.orientation
        quaternion = np.array([o.x, o.y, o.z, o.w], dtype=float)
        error = None
        if not self.active:
            error = INACTIVE
        elif np.all(np.abs(quaternion) < 1e-6):
            error = ZERO_QUATERNION
        if error is not None:
            logger.error(error)
            return response
        p = frame.pose.position
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_quat(quaternion).as_matrix()  # normalised, as tf2 does
        pose[:3, 3] = (p.x, p.y, p.z)
        source = self._aliases.get(frame.header.frame_id, frame.header.frame_id)
        with self.host.lock:
            q = self.host.sim.state().q
        try:  # the frame as the robot is now (tf2 at the latest time; a frame to itself needs no lookup)
            to_base = np.eye(4) if source == self._base else pose_between(frame_poses(self._tree, q), self._base,
                                                                            source)
        except KeyError as exc:
            logger.error(f'Could not transform {frame.header.frame_id} to robot base: {exc.args[0]}')
            return response
        selection = np.array([request.selection_vector_x, request.selection_vector_y, request.selection_vector_z,
                              request.selection_vector_rx, request.selection_vector_ry, request.selection_vector_rz])
        w, s = request.wrench, request.speed_limits
        speeds = np.array([s.linear.x, s.linear.y, s.linear.z, s.angular.x, s.angular.y, s.angular.z])
        limits = np.where(selection, speeds, np.asarray(request.deviation_limits, dtype=float))
        checks = ((not 1 <= request.type <= 3, f'The force mode type has to be 1, 2, or 3. Received {request.type}'),
                  (not 0.0 <= request.damping_factor <= 1.0,
                   f'The damping factor has to be between 0 and 1. Received {request.damping_factor:f}'),
                  (not 0.0 <= request.gain_scaling <= 2.0,
                   f'The gain scaling has to be between 0 and 2. Received {request.gain_scaling:f}'))
        for failed, text in checks:
            if failed:
                logger.error(text)
                return response
        if request.gain_scaling > 1.0:
            logger.warning('A gain_scaling >1.0 can make force mode unstable, e.g. in case of collisions or pushing '
                           f'against hard surfaces. Received {request.gain_scaling:f}')
        gain = float(request.gain_scaling)
        if self._cb3:
            if gain != 0.5:
                logger.warning(CB3_GAIN)
            gain = 1.0  # URScript's own default: a CB3 has no gain scaling
        spec = ForceModeSpec(to_base @ pose, selection.astype(bool),
                             np.array([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z]),
                             int(request.type), np.abs(limits), float(request.damping_factor), gain)
        with self.host.lock:
            if self.spec is None:
                self._velocity = np.zeros(6)
            self.spec = spec
        response.success = True
        logger.info(SET)
        return response

    def _on_stop(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        if not self.active:  # upstream waits for an update that never comes; ur_sim answers
            response.success, response.message = False, INACTIVE
            self.node.get_logger().error(INACTIVE)
            return response
        with self.host.lock:
            self._end()
        response.success = True
        self.node.get_logger().info(DISABLED)
        return response

    # ---- simulation loop, under the lock ----------------------------------------------------------------------
    def from_program(self, spec: ForceModeSpec | None) -> None:
        """A URScript program's force_mode (`spec`) or end_force_mode (None): the robot's one force mode, whatever
        the controller's state (the program, not the driver, commands the robot then)."""
        if spec is None:
            self._end()
            return
        if self.spec is None:
            self._velocity = np.zeros(6)
        self.spec = spec

    def _end(self) -> None:
        if self.spec is not None and self._offset is not None:
            self._hold = self._offset  # taken by the loop: the reference plus the offset, held
        self.spec = None
        self._target = None

    def take_hold(self, sample: TrajectorySample, state: ArmState) -> ArmState | None:
        """Once force mode has ended: the state the commander takes over from (`state` at the joint positions where
        force mode left the reference, at rest; after a deviation's protective stop where the arm is), else None."""
        if self._halt:
            self._halt = False
            return ArmState(state.t, state.q.copy(), np.zeros_like(state.q), state.effort)
        if self._hold is None:
            return None
        q = sample.positions + self._hold
        self._hold = self._offset = None
        return ArmState(state.t, q, np.zeros_like(q), state.effort)

    def update(self, cycle: Cycle) -> None:
        cause, self._stop_cause = self._stop_cause, None
        if cause is not None:  # the text the simulation loop logs for its own protective stops
            self.node.get_logger().error(f'PROTECTIVE_STOP: {cause}')

    def apply(self, sample: TrajectorySample, stop: np.ndarray | None, tcp_position: np.ndarray,
              tcp_velocity: np.ndarray, tcp_quaternion: np.ndarray, wrench: np.ndarray,
              dt: float) -> tuple[TrajectorySample, np.ndarray | None]:
        """The cycle's reference with force mode's offset: `tcp_*` the TCP now (base frame; its orientation as
        (x, y, z, w)), `wrench` (6,) the flange's reading (tool0 axes, the force the tool exerts on the arm), `dt`
        [s] the control period."""
        spec = self.spec
        if spec is None:
            return sample, stop
        tcp_rotation = Rotation.from_quat(tcp_quaternion).as_matrix()
        if self._offset is None:
            self._offset = np.zeros_like(sample.positions)
        r = force_frame(spec, tcp_position, tcp_velocity)
        if self._target is not None:  # the TCP now against where the program holds it now
            actual = np.eye(4)
            actual[:3, :3], actual[:3, 3] = tcp_rotation, tcp_position
            cause = deviation_cause(spec, deviation(r, actual, self._target))
            if cause is not None:
                return self._deviated(sample, stop, cause)
        applied_base = -np.concatenate((tcp_rotation @ wrench[:3], tcp_rotation @ wrench[3:]))
        applied = np.concatenate((r.T @ applied_base[:3], r.T @ applied_base[3:]))
        self._velocity = admittance_step(spec, self._velocity, applied, dt)
        twist = np.concatenate((r @ self._velocity[:3], r @ self._velocity[3:]))
        q = sample.positions + self._offset
        j = tool_jacobian(self._ik, q)
        qd = j.T @ np.linalg.solve(j @ j.T + _SINGULAR ** 2 * np.eye(6), twist)
        self._offset = self._offset + qd * dt
        moved = sample._replace(positions=sample.positions + self._offset, velocities=sample.velocities + qd)
        self._target = self._ik.fk(moved.positions)
        return moved, (moved.positions if stop is not None else None)

    def _deviated(self, sample: TrajectorySample, stop: np.ndarray | None,
                  cause: str) -> tuple[TrajectorySample, np.ndarray | None]:
        """The robot's protective stop for a deviation (`cause`): force mode ends, and the arm is held where it is
        from the next cycle on (this cycle keeps the last reference, as a stop seen in a cycle acts on the next)."""
        self.host.robot.protective_stop(self.host.sim.time, cause)
        self._stop_cause = cause
        held = sample._replace(positions=sample.positions + self._offset, velocities=np.zeros_like(sample.velocities))
        self.spec, self._target, self._offset, self._hold, self._halt = None, None, None, None, True
        return held, (held.positions if stop is not None else None)
