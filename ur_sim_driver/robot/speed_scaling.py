"""The emulated UR controller's own speed scaling: the robot slows itself when it cannot follow.

On a real UR the controller lowers its actual speed ("speed scaling", the driver's
``speed_scaling_factor`` state interface) when the commanded motion would exceed a joint limit, and the
driver's ``scaled_joint_trajectory_controller`` advances trajectory time by that factor, so the reference
waits for the arm instead of running away from it. Sources: the UR ROS 2 driver documentation (speed
scaling, ``ur_controllers``' scaled JTC: trajectory time advances by period x factor) and the UR manual's
description of speed scaling below joint speed and torque limits. UR does not publish the algorithm, so the
model below is ours; its two time constants are estimates chosen so that the driver's own integration tests
(``integration_test_scaled_joint_controller.py``: 1 rad in 0.5 s succeeds, 1 rad in 50 ms violates the path
tolerance) come out as on the real robot.

Model, per control cycle:

* target factor = min(1, velocity fraction, lag fraction), where the velocity fraction keeps the scaled
  reference velocity below 98 % of every joint's velocity limit, and the lag fraction falls linearly from 1 to
  0 as the arm's lag behind the reference grows from ``LAG_DEAD_ZONE`` to ``LAG_DEAD_ZONE + LAG_SPAN`` (the
  servo is limited in acceleration, or the joint torques saturate);
* the factor follows the target, falling by at most ``period / FALL_TIME`` per cycle (the robot's reaction
  time) and rising by at most ``period / RISE_TIME`` (it speeds up again gently).

The speed slider (``set_speed_slider``, the teach pendant's slider) multiplies it, as on the robot: the reported
factor (the hardware's ``speed_scaling_factor``) is ``slider x own slowdown``, and the scaled JTC advances trajectory
time by ``period x factor``. A new slider position is ramped so that the reference velocity changes at most at the
joints' acceleration limit (at once while the arm holds still), so that moving the slider does not jerk a moving arm.

A trajectory controller's own factor (``speed_scaling_input``, ros2_controllers' JTC) is not the robot's: it
lives in the controller (``motion/jtc.py``); the robot sees only the velocities it is asked for (``rate``).

A motion that is only mildly infeasible is slowed before its lag reaches the path tolerance (0.2 rad by
default); one that asks far too much (a step, 20 times the speed limit) runs away before the factor has
fallen and is aborted by the path tolerance, as on the real robot.
"""
from __future__ import annotations

import math

import numpy as np

FALL_TIME = 0.04  # [s] the factor can fall from 1 to 0 in this time (5 CB3 cycles, 20 e-series cycles)
RISE_TIME = 0.5  # [s] ... and rise from 0 to 1 in this time
LAG_DEAD_ZONE = 0.01  # [rad] lag the robot tolerates before slowing
LAG_SPAN = 0.1  # [rad] further lag at which the factor reaches 0
VELOCITY_MARGIN = 0.98  # fraction of the velocity limit the scaled reference may use
SLIDER_MIN, SLIDER_MAX = 0.01, 1.0  # the speed slider's range (set_speed_slider refuses anything else)


def velocity_fraction(rate: np.ndarray, v_max: np.ndarray, gain: float = 1.0) -> float:
    """Largest factor in [0, 1] keeping |rate x gain x factor| <= 98 % of v_max.

    Args:
        rate: (n,) reference velocity asked of the robot at factor 1 [rad/s].
        v_max: (n,) velocity limits [rad/s].
        gain: what already multiplies `rate` (the slider as applied).
    """
    # Largest demand relative to its limit decides; no division by a zero demand.
    # max() of a list: numpy's max costs more than the rest of this function for six joints.
    worst = max((np.abs(rate) / v_max).tolist()) * gain
    return 1.0 if worst <= VELOCITY_MARGIN else VELOCITY_MARGIN / worst


def lag_fraction(lag: np.ndarray) -> float:
    """Factor in [0, 1] from the largest lag (n,) [rad] of the arm behind the reference."""
    worst = max(map(abs, lag.tolist()), default=0.0)
    return min(1.0, max(0.0, 1.0 - (worst - LAG_DEAD_ZONE) / LAG_SPAN))


class RobotSpeedScaling:
    """The robot's actual speed scaling factor, updated once per control cycle.

    Args:
        v_max: (n,) joint velocity limits [rad/s].
        a_max: (n,) joint acceleration limits [rad/s^2] (for the slider's ramp).

    Attributes:
        own: the robot's own slowdown in [0, 1] (velocity and lag fractions, rate limited).
        slider: the speed slider position asked for, in [0.01, 1] (set by ``set_speed_slider``).
        slider_applied: the slider as applied (ramped towards `slider`, see the module docstring).
    """

    def __init__(self, v_max: np.ndarray, a_max: np.ndarray) -> None:
        self.v_max = np.asarray(v_max, dtype=float)
        self.a_max = np.asarray(a_max, dtype=float)
        self.own = 1.0
        self.slider = 1.0
        self.slider_applied = 1.0

    @property
    def factor(self) -> float:
        """The robot's speed scaling in [0, 1]: slider x own slowdown (the hardware's speed_scaling_factor, what
        the broadcaster reports and the scaled JTC advances by)."""
        return self.slider_applied * self.own

    def _ramp(self, rate: np.ndarray, gain: float, period: float) -> float:
        """Largest change of a multiplier of `rate` x `gain` in one period keeping the change of every joint's
        reference velocity within a_max x period (inf when nothing moves)."""
        speed = np.abs(rate) * gain
        with np.errstate(divide='ignore'):
            return float(np.min(np.where(speed > 0.0, self.a_max / speed, np.inf))) * period

    def update_at_rest(self, period: float) -> float:
        """`update` for a reference at rest (zero rate and lag), without its arithmetic: nothing moves, so the
        slider applies at once and the robot needs no slowdown of its own (target 1)."""
        self.slider_applied = self.slider
        self.own = min(max(1.0, self.own - period / FALL_TIME), self.own + period / RISE_TIME)
        return self.factor

    def update(self, rate: np.ndarray, lag: np.ndarray, period: float) -> float:
        """Advance one cycle and return the new factor (slider x own slowdown).

        Args:
            rate: (n,) reference velocity asked of the robot at factor 1 [rad/s].
            lag: (n,) reference - measured position [rad].
            period: control period [s].
        """
        if self.slider != self.slider_applied:
            ramp = self._ramp(rate, self.own, period)
            gap = self.slider - self.slider_applied
            self.slider_applied = self.slider if abs(gap) <= ramp else self.slider_applied + math.copysign(ramp, gap)
        # The slider already slows the reference: the robot's own slowdown is needed only beyond it.
        target = min(velocity_fraction(rate, self.v_max, self.slider_applied), lag_fraction(lag))
        step_down, step_up = period / FALL_TIME, period / RISE_TIME
        self.own = min(max(target, self.own - step_down), self.own + step_up)
        return self.factor
