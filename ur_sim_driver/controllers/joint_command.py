"""What a controller that moves the arm gives the robot every control cycle, and what the robot does without one.

In ros2_control such a controller writes the joints' command interfaces (``<joint>/position`` or ``/velocity``);
the UR hardware turns them into the robot's motion. Here the active one hands the robot's servo a reference
(:class:`~ur_sim_driver.motion.trajectory.TrajectorySample`) and the position it must not pass, from the simulation
loop under the simulation lock. The controller manager lets at most one be active (they claim the same joints'
interfaces, or modes the hardware cannot run together); with none active the robot holds where it is, or brakes
and holds where it comes to rest (:class:`HoldPosition`).
"""
from __future__ import annotations

import numpy as np

from ur_sim_driver.controllers.base import Component
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.urscript.moves import Speed


class JointCommander:
    """The commanding half of a controller (or the robot's own hold)."""

    def take_over(self, state: ArmState) -> None:
        """It commands the robot from this cycle on; `state` is the measured state now (under the lock).
        (Controllers set themselves up in their activate hook, which may run between cycles.)"""

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        """One control cycle under the lock: (the reference for the robot's servo, the stop position or None).

        Args:
            state: the measured state at the start of the cycle.
            period: the control period [s].
        """
        raise NotImplementedError

    def torques(self) -> np.ndarray | None:
        """Under the lock, after :meth:`command`: the joint torques (n,) [N m] the robot applies on top of its gravity
        compensation when this commander controls torque (the driver's effort interface), else None (the robot's
        servo follows the reference)."""
        return None

    def halt(self, q: np.ndarray, reason: str) -> None:
        """The robot cancelled the motion (a tool contact): stop commanding motion, hold `q` (n,) [rad] and end
        any goal, naming `reason`. Called under the lock between two cycles."""


class JointCommandController(Component, JointCommander):
    """A controller that claims joint command interfaces (trajectory and forward controllers).

    Attributes:
        stop_reason: set by the controller_stopper before it deactivates the controller: why the robot cannot move
            (None when a switch_controller request deactivates it).
    """

    initially_active = False

    def __init__(self) -> None:
        super().__init__()
        self.stop_reason: str | None = None

    def robot_refusal(self) -> str | None:
        """Under the lock: why the robot's state keeps this controller from taking a goal now, or None (the
        controller_stopper keeps a controller inactive while the robot cannot move, so this comes first)."""
        refusal = self.host.robot.motion_refusal()
        return None if refusal is None else f'the controller is not running: {refusal}'


class HoldPosition(JointCommander):
    """The robot without an active joint controller. Taken over at rest it holds the measured position, as the UR
    hardware keeps its last position command. Taken over from a moving arm (:meth:`stop`) it brakes as the driver's
    program does when no controller commands (stopj: linear in joint space, the leading joint at a given
    deceleration) and holds where the arm comes to rest.
    """

    def __init__(self) -> None:
        self._sample: TrajectorySample | None = None  # the hold (where the braking ends)
        self._braking: Speed | None = None
        self._elapsed = 0.0  # [s] since the braking began
        self._limits: tuple[np.ndarray, np.ndarray] | None = None

    def take_over(self, state: ArmState) -> None:
        zero = np.zeros_like(state.q)
        self._sample = TrajectorySample(state.q.copy(), zero, zero.copy(), 0, True)
        self._braking = None

    def stop(self, state: ArmState, deceleration: float, q_min: np.ndarray, q_max: np.ndarray) -> None:
        """Take over from a moving arm: brake from the measured state (stopj, the leading joint at `deceleration`
        [rad/s^2]) and hold where it comes to rest, within `q_min`, `q_max` (n,) [rad]; not back where the last
        controller left off."""
        self.take_over(state)
        if not np.any(state.qd):
            return
        self._braking = Speed(state.q, state.qd, np.zeros_like(state.qd), deceleration, None)
        self._elapsed = 0.0
        self._limits = (q_min, q_max)
        rest = np.clip(self._braking.sample(self._braking.duration)[0], q_min, q_max)
        self._sample = TrajectorySample(rest, self._sample.velocities, self._sample.accelerations, 0, True)

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        if self._sample is None:
            self.take_over(state)
        if self._braking is not None:
            # From the measured state on, one sample a period (the servo takes it up where the controller's
            # reference left it); the hold is the stop point the servo does not pass.
            if self._elapsed < self._braking.duration:
                q, qd, qdd = self._braking.sample(self._elapsed)
                self._elapsed += period
                return TrajectorySample(np.clip(q, *self._limits), qd, qdd, 0, False), self._sample.positions
            self._braking = None
        return self._sample, self._sample.positions
