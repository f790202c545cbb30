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

Time is explicit: :meth:`JointServo.step` takes the control period. The per-joint law is compiled with numba
(``servo_kernel``): in Python it cost about 20 us of every control cycle.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import F8, IN1, OUT2, VOID

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
        n = len(positions)
        # (2, n): the generator's position [rad] and velocity [rad/s], advanced in place by servo_kernel.
        self.state = np.zeros((2, n))
        self.state[0] = positions
        self.gain = _GAIN_TIMES_PERIOD * control_rate  # [1/s]
        self._no_stop = np.full(n, np.nan)

    def reset(self, positions: np.ndarray, velocities: np.ndarray) -> None:
        """Restart from a measured state (n,) [rad], [rad/s]."""
        self.state[0] = positions
        self.state[1] = velocities

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
        out = np.empty((4, len(r)))
        servo_kernel(np.asarray(r, dtype=float), np.asarray(rd, dtype=float), np.asarray(rdd, dtype=float),
                     self.state, limits.v_max, limits.a_max, limits.a_stop, limits.q_min, limits.q_max,
                     self._no_stop if stop is None else np.asarray(stop, dtype=float), dt, self.gain, out)
        return Setpoint(out[0], out[1], out[2], out[3] != 0.0)


@njit(F8(F8, F8, F8, F8, F8, F8, F8, F8), cache=True)
def _brake(p: float, v: float, v_next: float, q_min: float, q_max: float, stop: float, a: float,
           dt: float) -> float:
    """Limit one joint's next velocity to one that can still stop at every stop point ahead: both position
    limits and `stop` [rad] (NaN: none).

    Discrete form of v <= sqrt(2 a d): moving at the mean of v and v_next for one period, then braking at `a`,
    must end before the stop point: (v + v_next) dt / 2 + v_next^2 / (2 a) <= d.
    """
    if v_next == 0.0:
        return v_next
    toward = 1.0 if v_next > 0.0 else -1.0
    # The nearest stop point in the direction of motion.
    distance = (q_max - p) if toward > 0.0 else (p - q_min)
    if (stop - p) * toward > 0.0:  # a stop point behind, or exactly here, does not brake (nor does NaN)
        distance = min(distance, (stop - p) * toward)
    distance = max(distance, 0.0)
    half = 0.5 * a * dt
    room = max(distance - 0.5 * max(v * toward, 0.0) * dt, 0.0)
    allowed = math.sqrt(half * half + 2.0 * a * room) - half
    return toward * allowed if abs(v_next) > allowed else v_next


@njit(VOID(IN1, IN1, IN1, OUT2, IN1, IN1, IN1, IN1, IN1, IN1, F8, F8, OUT2), cache=True)
def servo_kernel(r, rd, rdd, state, v_max, a_max, a_stop, q_min, q_max, stop, dt, gain, out):
    """One cycle of the setpoint generator, compiled (it runs every control cycle).

    Args:
        r, rd, rdd: (n,) reference [rad], [rad/s], [rad/s^2].
        state: (2, n) the generator's position [rad] and velocity [rad/s]; advanced in place.
        v_max, a_max, a_stop, q_min, q_max: (n,) the limits (see ServoLimits).
        stop: (n,) positions not to pass [rad]; NaN where there is none.
        dt: control period [s]; gain: [1/s] of the approach law's linear part.
        out: (4, n) written: setpoint position, velocity, acceleration, and 1.0 where a limit binds.
    """
    for k in range(r.shape[0]):
        rk, rdk, rddk, pk, vk, vm, am = r[k], rd[k], rdd[k], state[0, k], state[1, k], v_max[k], a_max[k]
        # On the reference: within what one period of the acceleration limit can change (the setpoint's
        # own integration drifts from a cubic or quintic by jerk dt^3, far less), and it is feasible.
        on_ref = (abs(rdk) <= vm and abs(rddk) <= am and abs(pk - rk) <= am * dt * dt
                  and abs(vk - rdk) <= am * dt)
        if on_ref:
            a = rddk
        else:
            # Aim at the reference velocity plus the approach velocity of the remaining gap.
            gap = rk - pk
            d = abs(gap)
            approach = min(gain * d, math.sqrt(2.0 * _APPROACH_SHARE * am * d))
            v_goal = rdk + (approach if gap > 0.0 else -approach)
            a = min(max((v_goal - vk) / dt, -am), am)
        v_free = vk + a * dt
        v_new = min(max(v_free, -vm), vm)
        v_new = _brake(pk, vk, v_new, q_min[k], q_max[k], stop[k], a_stop[k], dt)
        if not (on_ref and v_new == v_free):
            a = (v_new - vk) / dt
        sp_p, sp_v = (rk, rdk) if on_ref else (pk, vk)
        out[0, k], out[1, k], out[2, k], out[3, k] = sp_p, sp_v, a, 0.0 if on_ref else 1.0
        # Advance with constant acceleration over the period (exact for the double integrator).
        state[0, k] = sp_p + sp_v * dt + 0.5 * a * dt * dt
        state[1, k] = sp_v + a * dt
