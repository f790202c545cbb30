"""freedrive_mode_controller: ``~/enable_freedrive_mode`` (std_msgs/Bool).

Upstream (ur_controllers' FreedriveModeController): while the controller is active, a true message starts
freedrive and a false one ends it; every message restarts a wall-clock timer, and when no message has arrived
for ``inactive_timeout`` (10 s, upstream's default) freedrive ends ("the client is not reachable"). Messages
while the controller is inactive are ignored; deactivation ends freedrive. The controller claims
``<tf_prefix>freedrive_mode/{async_success, enable, abort}``: the hardware runs it alone (no position, velocity
or passthrough controller beside it, ``ur_hardware.py``).

In ur_sim freedrive is a torque mode of the robot (``Simulator.advance_free``): gravity and Coriolis torques of
the model are compensated, the joints are free with light damping, and the robot's limits still hold; so the
arm moves under external forces (``/ur_sim/apply_wrench`` in a test, ``sim_wrench.py``). Outside freedrive
(controller active but not enabled) the robot holds the position where freedrive ended, resisting pushes.
"""
from __future__ import annotations

import time

import numpy as np
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from std_msgs.msg import Bool

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.controllers.joint_command import JointCommandController
from ur_sim_driver.controllers.ur_hardware import FREEDRIVE
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.sim_config import SimConfig

NAME = 'freedrive_mode_controller'
TYPE = 'ur_controllers/FreedriveModeController'
INACTIVE_TIMEOUT = 10.0  # [s] of wall time without a message before freedrive ends (upstream's default)


class FreedriveModeController(JointCommandController):
    """The driver's freedrive_mode_controller.

    Attributes:
        inactive_timeout: [s] of wall time without a message after which freedrive ends.
        free: the robot is in freedrive now (read by the simulation loop under the lock).
    """

    name = NAME
    type_name = TYPE

    def __init__(self, inactive_timeout: float = INACTIVE_TIMEOUT) -> None:
        super().__init__()
        self.inactive_timeout = inactive_timeout
        self.free = False
        self._requested: bool | None = None  # the latest request not yet applied by the loop (under the lock)
        self._last_message = 0.0  # time.monotonic() of the last message
        self._hold: np.ndarray | None = None

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        return tuple(f'{cfg.tf_prefix}{FREEDRIVE}/{n}' for n in ('async_success', 'enable', 'abort')), ()

    def on_configure(self, host: Host, node: Node) -> None:
        node.create_subscription(Bool, host.cfg.prefixed(f'{self.name}/enable_freedrive_mode'), self._on_enable, 10,
                                 callback_group=MutuallyExclusiveCallbackGroup())

    def _on_enable(self, msg: Bool) -> None:
        with self.host.lock:
            self._last_message = time.monotonic()
            if self.active and bool(msg.data) != (self.free if self._requested is None else self._requested):
                self._requested = bool(msg.data)

    # ---- simulation loop, under the lock ---------------------------------------------------------------------
    def on_activate(self) -> None:
        self.stop_reason = None
        self.free, self._requested = False, None
        self._hold = self.host.sim.state().q.copy()

    def on_deactivate(self) -> None:
        if self.free:
            self.node.get_logger().info('Freedrive mode has been disabled successfully.')
        self.free, self._requested = False, None

    def take_over(self, state: ArmState) -> None:
        self._hold = state.q.copy()

    def _stopping_point(self, state: ArmState) -> np.ndarray:
        # Leaving freedrive while the arm moves: it holds where it can stop, braking as hard as the robot does.
        return self.host.sim.stopping_point(state)

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        log = self.node.get_logger()
        if self._requested is not None:
            on, self._requested = self._requested, None
            log.info(f'Received command to {"start" if on else "stop"} Freedrive Mode.')
            self.free = on
            log.info(f'Freedrive mode has been {"enabled" if on else "disabled"} successfully.')
            if not on:
                self._hold = self._stopping_point(state)
        elif self.free and time.monotonic() - self._last_message > self.inactive_timeout:
            log.info('Freedrive mode will be deactivated since client is not reachable.')
            self.free = False
            self._hold = self._stopping_point(state)
        # In freedrive the loop applies torques itself; the reference (the measured state at rest) only feeds the
        # safety check and the controllers' state.
        target = state.q.copy() if self.free or self._hold is None else self._hold
        zero = np.zeros_like(state.q)
        host = self.host
        host.speed_scaling.update_at_rest(period)
        return TrajectorySample(target, zero, zero.copy(), 0, True), target
