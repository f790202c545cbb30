"""A trajectory's start stamp far ahead of the simulated clock: accepted (upstream's JTC waits for it), and said.

No rclpy here: the gateway logs what :func:`far_start` returns.
"""
from __future__ import annotations

from typing import NamedTuple

# A start stamp this far ahead of the simulated clock is accepted (upstream does) but logged [s].
FAR_FUTURE = 5.0
# A stamp this close to the wall clock [s], on a simulated clock this far from it, is a client on the wall clock.
WALL_CLOCK_NEAR = 3600.0


class FarStart(NamedTuple):
    """A start stamp far ahead of the simulated clock: the log line, and whether it looks like a wall-clock stamp."""

    text: str
    wall_clock: bool


def far_start(stamp: float, now: float, wall: float) -> FarStart | None:
    """What to log about a trajectory stamped to start at `stamp` [s] when the simulated time is `now` [s] and the
    wall clock `wall` [s since the epoch]; None within FAR_FUTURE.

    A start a few seconds ahead is a client's choice (a goal stamped ahead of its delivery), not an error: said at
    info level. Only a stamp near the wall clock on a simulated clock far from it is blamed on the client's clock.
    """
    ahead = stamp - now
    if ahead <= FAR_FUTURE:
        return None
    text = f'starts at header.stamp {stamp:.3f} s, {ahead:.1f} s after the simulated time now ({now:.3f} s); ' \
           'it waits until then'
    if abs(stamp - wall) < WALL_CLOCK_NEAR < abs(now - wall):
        return FarStart(text + ('. The stamp is the wall clock\'s time while ur_sim runs on simulated time: '
                                'the client needs use_sim_time:=true (a zero stamp starts at once).'), True)
    return FarStart(text + '.', False)
