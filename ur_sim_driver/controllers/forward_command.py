"""forward_position_controller, forward_velocity_controller and forward_effort_controller (ros2_controllers'
JointGroup*Controller).

``~/commands`` (std_msgs/Float64MultiArray): one value per joint in the controller's joint order, written to the
joints' position or velocity command interfaces each cycle. On the UR these become servoj / speedj targets, which
the robot follows within its own limits; here they become the reference of the robot's servo (``servo.py``),
so the velocity, acceleration and position limits hold as for any reference:

* position: the commanded positions, at rest; the servo moves there as fast as the limits allow and stops
  there (a target beyond a position limit drives the joint into it: a protective stop, as on the robot);
* velocity: the commanded velocities, reached at the robot's acceleration limit (the reference integrates a
  velocity ramped at that limit, so the servo can follow it exactly), capped at the velocity limits.

* effort: the commanded joint torques, on top of the robot's gravity compensation and within its effort limits
  (``Simulator.advance_torque``, ``robot/direct_torque.py``); the hardware starts effort mode only on robot
  software 5.23.0 / 10.10.0 or later, and only without another joint mode. Until the first message the torques
  are zero (the arm, gravity-compensated, stays where it is); no joint is driven past its speed limit, and the
  robot's safety system stops a joint that could no longer stop before a position limit.

A message with the wrong number of values or a non-finite value is refused with a log line naming it (upstream
logs the size in its update and keeps the previous command; refusing it on arrival keeps the same command).
While the controller is inactive its messages are dropped, and activation starts from no command: the robot
holds the position (position), stands still (velocity) or gets zero torques (effort) until the first message, as
upstream resets its command buffer on activation. Deactivated, the effort controller's torques are gone (the
hardware zeroes them) and the robot brakes as the driver's program does (stopj) and holds where it comes to rest.
"""
from __future__ import annotations

import math

import numpy as np
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from std_msgs.msg import Float64MultiArray

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.controllers.joint_command import JointCommandController
from ur_sim_driver.controllers.ur_hardware import EFFORT, POSITION, VELOCITY, joint_interfaces, prefixed_joints
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.sim_config import SimConfig

TYPES = {POSITION: 'position_controllers/JointGroupPositionController',
         VELOCITY: 'velocity_controllers/JointGroupVelocityController',
         EFFORT: 'effort_controllers/JointGroupEffortController'}
INACTIVE = "Can't accept new commands. subscriber is inactive"
# A velocity reference stops integrating this far beyond a position limit: far enough that the joint is driven
# into the limit (a protective stop, as a speedj into a limit gives), near enough to stop there at once.
_LIMIT_OVERRUN = 0.01  # [rad]


def check_command(values: list[float] | np.ndarray, joints: tuple[str, ...]) -> str | None:
    """Why a command cannot be used (size, non-finite value), or None."""
    if len(values) != len(joints):
        return f'command size ({len(values)}) does not match number of interfaces ({len(joints)})'
    for name, v in zip(joints, values):
        if not math.isfinite(v):
            return f'command for {name} is {v}: not a finite number'
    return None


class ForwardCommandController(JointCommandController):
    """One forward command controller: `kind` is 'position', 'velocity' or 'effort'."""

    def __init__(self, kind: str) -> None:
        super().__init__()
        if kind not in TYPES:
            raise ValueError(f"forward command kind {kind!r} is not one of {', '.join(TYPES)}")
        self.kind = kind
        self.name = f'forward_{kind}_controller'
        self.type_name = TYPES[kind]
        self._target: np.ndarray | None = None  # the latest command (under the lock)
        self._r = np.zeros(0)  # velocity: reference position [rad] and velocity [rad/s]
        self._rd = np.zeros(0)

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return joint_interfaces(prefixed_joints(cfg.joints, cfg.tf_prefix), self.kind), ()

    def on_configure(self, host: Host, node: Node) -> None:
        self._joints = tuple(host.sim.joint_names)
        node.create_subscription(Float64MultiArray, host.cfg.prefixed(f'{self.name}/commands'), self._on_commands,
                                 10, callback_group=MutuallyExclusiveCallbackGroup())

    def _on_commands(self, msg: Float64MultiArray) -> None:
        if not self.active:
            self.node.get_logger().warning(INACTIVE)
            return
        values = list(msg.data)
        reason = check_command(values, self._joints)
        if reason is not None:
            self.node.get_logger().error(f'Ignored ~/commands: {reason}')
            return
        with self.host.lock:
            if self.active:
                self._target = np.array(values, dtype=float)

    # ---- simulation loop, under the lock --------------------------------------------------------------------------
    def on_activate(self) -> None:
        self.stop_reason = None
        self._target = None
        self._r = self.host.sim.state().q.copy()  # the hardware starts from the measured position, at rest
        self._rd = np.zeros_like(self._r)

    def on_deactivate(self) -> None:
        self._target = None

    def halt(self, q: np.ndarray, reason: str) -> None:
        # The robot dropped the motion; the next message commands it again (as a servoj/speedj after the robot
        # left its tool-contact mode).
        self._target = None
        self._r = np.array(q, dtype=float)
        self._rd = np.zeros_like(self._r)

    def torques(self) -> np.ndarray | None:
        if self.kind != EFFORT:
            return None
        return np.zeros(len(self._r)) if self._target is None else self._target

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        zero = np.zeros_like(state.q)
        host = self.host
        if self.kind == EFFORT:
            # The robot applies the torques (torques()); the reference, the arm where it is at rest, only feeds the
            # controllers' state and the safety check (which watches the measured motion under torque control).
            host.speed_scaling.update_at_rest(period)
            return TrajectorySample(state.q.copy(), zero, zero.copy(), 0, True), None
        if self.kind == POSITION:
            target = self._r if self._target is None else self._target
            # At rest at the target, which is also where the servo must stop.
            sample = TrajectorySample(target.copy(), zero, zero.copy(), 0, True)
            host.speed_scaling.update_at_rest(period)
            return sample, target
        p = host.sim.params
        wanted = zero if self._target is None else np.clip(self._target, -p.v_max, p.v_max)
        # Constant acceleration over the period, as the servo integrates: it can follow this reference exactly.
        a = np.clip(wanted - self._rd, -host.sim.a_max * period, host.sim.a_max * period) / period
        sample = TrajectorySample(self._r.copy(), self._rd.copy(), a, 0, True)
        self._r = self._r + self._rd * period + 0.5 * a * period * period
        self._rd = self._rd + a * period
        beyond = (self._r > p.q_max + _LIMIT_OVERRUN) | (self._r < p.q_min - _LIMIT_OVERRUN)
        if beyond.any():
            self._rd[beyond] = 0.0
            self._r = np.clip(self._r, p.q_min - _LIMIT_OVERRUN, p.q_max + _LIMIT_OVERRUN)
        host.speed_scaling.update_at_rest(period)
        return sample, None
