"""Why a plan failed, in the Teach tab's words: which waypoint the robot cannot reach, and why.

The planner's own message names IK branches and arc lengths (20 lines for one unreachable waypoint). The Teach
tab already checks every waypoint (reach.py); when a waypoint the plan uses is unreachable, that is the reason
given ("waypoint 13: out of reach (48 mm)"), numbered as the page numbers them. Otherwise the planner's message is
shortened to its gist.
"""
from __future__ import annotations

import re
from collections.abc import Sequence

from ur_glue_planner.studio.reach import ReachResult

MAX_NAMED = 3  # unreachable waypoints named in one message; the rest are counted
MAX_CHARS = 240  # of a planner message shown as it is


def short_reason(reason: str) -> str:
    """The reach check's reason, short: 'out of reach (48 mm)' for a tip that no joint positions put there."""
    out = re.match(r'no IK solution: out of reach \(residual ([0-9.]+) mm', reason)
    if out:
        return f'out of reach ({float(out.group(1)):.0f} mm)'
    return reason


def unreachable(results: Sequence[ReachResult | None], planned: Sequence[int]) -> list[str]:
    """'waypoint <number>: <reason>' of each planned waypoint (indices from 0, numbers from 1) found unreachable."""
    return [f'waypoint {k + 1}: {short_reason(results[k].reason)}' for k in planned
            if k < len(results) and results[k] is not None and not results[k].reachable]


def gist(planner_message: str) -> str:
    """The planner's message, short: for 'no IK branch follows the whole bead', how far the best branch got;
    others cut at MAX_CHARS."""
    if planner_message.startswith('no IK branch follows the whole bead'):
        reached = [float(s) for s in re.findall(r'IK fails at s = ([0-9.]+) m', planner_message)]
        if reached:
            return (f'no IK branch follows the whole bead: the best stops {max(reached):.3f} m along it '
                    '(the waypoints there are each reachable, but not in one arm configuration)')
    text = ' '.join(planner_message.split())
    return text if len(text) <= MAX_CHARS else text[:MAX_CHARS - 3] + '...'


def plan_failure(planner_message: str, results: Sequence[ReachResult | None], planned: Sequence[int]) -> str:
    """What to tell the user when planning failed: the unreachable planned waypoints if any, else the gist."""
    named = unreachable(results, planned)
    if not named:
        return gist(planner_message)
    more = len(named) - MAX_NAMED
    return '; '.join(named[:MAX_NAMED]) + (f'; and {more} more unreachable' if more > 0 else '')
