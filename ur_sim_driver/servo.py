"""The robot's own setpoint generator: what the emulated UR controller actually commands its joints to do.

The JTC reference may be infeasible (a velocity step at a corner of a positions-only trajectory, a segment
faster than the joints can move). A real UR never exceeds its joint limits: it follows the reference as far
as its limits allow, lags behind where they bind, and lowers its speed scaling (``speed_scaling.py``) so that
the reference waits for it. This module is the first half of that: per joint, a setpoint (position,
velocity) that

* equals the reference exactly while the reference is feasible (so feasible motions are tracked as before);
* otherwise moves towards it with |velocity| <= v_max and |acceleration| <= a_max, closing the gap with a
  square-root law (the time-optimal approach of a double integrator with bounded acceleration), which
  reaches the reference from behind without passing it;
* never passes a stop point: the trajectory's final position while the last segment runs (or the hold
  position), and the joint's position limits. It brakes with the velocity allowed by the remaining distance,
  sqrt(2 a d), so a commanded final point is not overshot even when the reference stops abruptly.

Time is explicit: :meth:`JointServo.step` takes the control period.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The sqrt law plans the approach with this share of the acceleration limit: the rest absorbs the control
# period's discreteness, so the setpoint reaches the reference from behind instead of passing it.
_APPROACH_SHARE = 0.5
# Share of the control rate used as the gain of the linear part of the approach law (as torque_control.py).
_GAIN_TIMES_PERIOD = 0.3


@dataclass(frozen=True, eq=False)
class ServoLimits:
    """Per-joint limits the setpoint respects.

    Attributes:
        v_max: (n,) velocity limits [rad/s].
        a_max: (n,) acceleration limits for following the reference [rad/s^2].
        a_stop: (n,) deceleration limits for stopping at a stop point or a position limit [rad/s^2]
            (at least a_max: the arm brakes harder than it plans, as a robot does).
        q_min, q_max: (n,) position limits [rad].
    """

    v_max: np.ndarray
    a_max: np.ndarray
    a_stop: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray


@dataclass(frozen=True, eq=False)
class Setpoint:
    """What the joint controller tracks in one cycle.

    Attributes:
        positions, velocities, accelerations: (n,) [rad], [rad/s], [rad/s^2].
        limited: (n,) bool, True where the setpoint differs from the reference (a limit binds).
    """

    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    limited: np.ndarray


def approach_velocity(distance: np.ndarray, gain: float, a_max: np.ndarray) -> np.ndarray:
    """Velocity [rad/s] at which to close a gap of `distance` (n,) [rad]: linear near 0, sqrt(2 a d) far away.

    The two branches meet where gain * d = sqrt(2 a d); taking the smaller keeps the law continuous and
    never asks for a deceleration above a_max.
    """
    d = np.abs(distance)
    return np.sign(distance) * np.minimum(gain * d, np.sqrt(2.0 * _APPROACH_SHARE * a_max * d))


class JointServo:
    """Setpoint generator of n joints; one :meth:`step` per control cycle.

    Args:
        positions: (n,) initial setpoint = measured position [rad].
        control_rate: [Hz], sets the gain of the linear part of the approach law.
    """

    def __init__(self, positions: np.ndarray, control_rate: float) -> None:
        self._p = np.array(positions, dtype=float)
        self._v = np.zeros_like(self._p)
        self._gain = _GAIN_TIMES_PERIOD * control_rate

    def reset(self, positions: np.ndarray, velocities: np.ndarray) -> None:
        """Restart from a measured state (n,) [rad], [rad/s]."""
        self._p = np.array(positions, dtype=float)
        self._v = np.array(velocities, dtype=float)

    def step(self, r: np.ndarray, rd: np.ndarray, rdd: np.ndarray, dt: float, limits: ServoLimits,
             stop: np.ndarray | None = None) -> Setpoint:
        """The setpoint for this cycle, given the reference now.

        Args:
            r, rd, rdd: (n,) reference position [rad], velocity [rad/s], acceleration [rad/s^2] in real time
                (already multiplied by the speed scaling).
            dt: control period [s].
            limits: the joints' limits this cycle.
            stop: (n,) positions the setpoint must not pass (the trajectory's final point), or None.

        Returns:
            The setpoint; the generator's state advances to the next cycle.
        """
        p, v = self._p, self._v
        feasible = (np.abs(rd) <= limits.v_max) & (np.abs(rdd) <= limits.a_max)
        # On the reference: within what one period of the acceleration limit can change (the setpoint's own
        # integration drifts from a cubic or quintic by jerk dt^3, far less).
        on_ref = (np.abs(p - r) <= limits.a_max * dt * dt) & (np.abs(v - rd) <= limits.a_max * dt) & feasible
        # Off the reference: aim at the reference velocity plus the approach velocity of the remaining gap.
        v_goal = rd + approach_velocity(r - p, self._gain, limits.a_max)
        a = np.clip((v_goal - v) / dt, -limits.a_max, limits.a_max)
        a = np.where(on_ref, rdd, a)
        v_next = np.clip(v + a * dt, -limits.v_max, limits.v_max)
        v_next = self._brake(p, v, v_next, limits.q_min, limits.a_stop, dt, toward=-1.0)
        v_next = self._brake(p, v, v_next, limits.q_max, limits.a_stop, dt, toward=+1.0)
        if stop is not None:
            ahead = np.sign(stop - p)
            braked = self._brake(p, v, v_next, stop, limits.a_stop, dt, toward=np.where(ahead != 0.0, ahead, 1.0))
            v_next = np.where(ahead != 0.0, braked, v_next)
        a = np.where(on_ref & (v_next == v + a * dt), a, (v_next - v) / dt)
        setpoint = Setpoint(np.where(on_ref, r, p), np.where(on_ref, rd, v), a, ~on_ref)
        # Advance with constant acceleration over the period (exact for the double integrator).
        self._p = setpoint.positions + setpoint.velocities * dt + 0.5 * a * dt * dt
        self._v = setpoint.velocities + a * dt
        return setpoint

    @staticmethod
    def _brake(p: np.ndarray, v: np.ndarray, v_next: np.ndarray, stop: np.ndarray, a: np.ndarray,
               dt: float, toward: float | np.ndarray) -> np.ndarray:
        """Limit the next velocity towards `stop` (direction `toward`, +-1) to one that can still stop there.

        Discrete form of v <= sqrt(2 a d): moving at the mean of v and v_next for one period, then braking
        at `a`, must end before `stop`: (v + v_next) dt / 2 + v_next^2 / (2 a) <= d.
        """
        distance = np.maximum((stop - p) * toward, 0.0)
        speed = np.maximum(v * toward, 0.0)
        half = 0.5 * a * dt
        room = np.maximum(distance - 0.5 * speed * dt, 0.0)
        v_allowed = -half + np.sqrt(half * half + 2.0 * a * room)
        moving_toward = v_next * toward > 0.0
        return np.where(moving_toward & (np.abs(v_next) > v_allowed), toward * v_allowed, v_next)
