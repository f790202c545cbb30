"""What the page says about the live robot: waiting for it, live, or gone (no joint states for a while).

When ur_sim stopped, the last pose stayed on the page as if the robot were there, and a live viewer started before
the robot was a blank page. The status line tells these apart from the wall time since the last joint state.
"""
from __future__ import annotations

import html

GONE_AFTER = 3.0  # [s] of wall time without a joint state after which the robot is reported gone
LIVE_COLOR, WAIT_COLOR, GONE_COLOR = '#1e8c3a', '#b06d00', '#c0262d'


def robot_status(prefix: str, now: float, last_joint_state: float | None, has_description: bool,
                 gone_after: float = GONE_AFTER) -> tuple[str, str]:
    """(state, text) of the live robot: state is 'waiting', 'live' or 'gone'.

    Args:
        prefix: Namespace of the topics, '' or e.g. '/ur10'.
        now: Wall time now [s] (the clock of ``last_joint_state``).
        last_joint_state: Wall time [s] the newest joint state arrived, None before the first.
        has_description: Whether the robot description has arrived.
        gone_after: [s] without a joint state after which the robot counts as gone.
    """
    joint_states, description = f'{prefix}/joint_states', f'{prefix}/robot_description'
    if last_joint_state is None:
        also = '' if has_description else f' and {description}'
        return 'waiting', f'waiting for {joint_states}{also}'
    silent = now - last_joint_state
    if silent > gone_after:
        return 'gone', (f'robot gone: no {joint_states} for {silent:.0f} s (more than {gone_after:g} s); '
                        'the last pose stays drawn')
    if not has_description:
        return 'waiting', f'waiting for {description} ({joint_states} arrive)'
    return 'live', f'robot live: {joint_states}'


def no_ros_status() -> tuple[str, str]:
    """The status of a studio without a ROS connection (teaching and preview only)."""
    return 'waiting', 'no ROS connection: teaching and preview only'


def status_html(state: str, text: str) -> str:
    """A block of fixed height (two lines, so that nothing below it moves): a coloured dot and the text."""
    color = {'live': LIVE_COLOR, 'gone': GONE_COLOR}.get(state, WAIT_COLOR)
    return (f'<div class="studio-robot-status" data-state="{state}" style="height:2.7em;overflow:hidden;'
            f'line-height:1.35em;font-size:0.9em"><span style="color:{color}">&#9679;</span> '
            f'<b>Robot</b>: {html.escape(text)}</div>')
