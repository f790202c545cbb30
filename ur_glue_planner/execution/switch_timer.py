"""Trajectory time of a running goal, on the controller's own clock, and the switch events due by then.

The trajectory controller advances a goal's time by ``period x speed scaling factor`` each cycle (the UR
driver's scaled JTC; ur_sim the same), so with the speed slider at 50 % or the robot slowed by a safety
function, the bead start arrives later in wall and robot time than its ``time_from_start``. The planner
therefore does not switch on a timer: it integrates the factor that the controller publishes with every
``controller_state`` message (``speed_scaling_factor``, stamped with the robot's time) from the goal's start
stamp, and switches when that trajectory time reaches the planned switch time. Before the start stamp the
clock runs unscaled (the goal has not started), so a switch planned before the motion (seed 1's, which
starts at rest on the bead) happens that long before the start. Pure: no ROS here.
"""
from __future__ import annotations

from dataclasses import dataclass


class ScaledClock:
    """Trajectory time [s] from (robot stamp [s], speed scaling factor) samples, goal started at ``start``."""

    def __init__(self, start: float) -> None:
        self.start = start
        self._t = 0.0
        self._last: float | None = None
        self.now = float('-inf')  # the value the last update returned

    def update(self, stamp: float, factor: float) -> float:
        """Advance to ``stamp`` with the factor the controller used since the previous sample; return the
        trajectory time (negative before the start)."""
        if stamp <= self.start:
            self._last = None
            self.now = stamp - self.start
            return self.now
        since = self.start if self._last is None else self._last
        if stamp > since:
            self._t += (stamp - since) * max(factor, 0.0)  # the plain JTC's own factor may exceed 1
            self._last = stamp
        self.now = self._t
        return self._t

    @property
    def time(self) -> float:
        return self._t


@dataclass(frozen=True)
class SwitchEvent:
    """Set digital output ``pin`` to ``state`` at trajectory time ``t`` [s]."""

    t: float
    pin: int
    state: bool
    what: str


class SwitchSequence:
    """Events in time order; :meth:`due` hands each one out once, when the trajectory time reaches it.

    Args:
        events: The switch events.
        half_period: [s] an event is due half a control period early, so that the call lands in the cycle
            nearest to its time rather than always after it.
    """

    def __init__(self, events: list[SwitchEvent], half_period: float = 0.0) -> None:
        self._pending = sorted(events, key=lambda e: e.t)
        self.half_period = half_period

    def due(self, t: float) -> list[SwitchEvent]:
        """Events with time <= t + half_period, removed from the pending ones."""
        n = 0
        while n < len(self._pending) and self._pending[n].t <= t + self.half_period:
            n += 1
        out, self._pending = self._pending[:n], self._pending[n:]
        return out

    @property
    def pending(self) -> list[SwitchEvent]:
        return list(self._pending)
