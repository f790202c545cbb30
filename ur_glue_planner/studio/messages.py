"""The studio's message log: the last few lines in a box of fixed height, cleared when a new action starts.

A box that grew with its lines moved every control below it (a Stop click landed beside the button during a run);
errors of an earlier action stayed on screen after the next one had started. Here the box always takes the same
height, and :meth:`MessageLog.begin` (Load, Plan, Run, Save) replaces what an earlier action said.
"""
from __future__ import annotations

import html
import re

SHOWN = 5  # lines in the box
HISTORY = 200  # lines kept in `history` (for tests and a look back), oldest dropped
LINE_HEIGHT = 1.35  # [em] of one line in the box
# Words of a line that reports a failure (whole words: 'error_code 0' of a success is none)
ERROR_WORDS = re.compile(r'\b(failed|cannot|error|refused|gone|missed|stopped)\b')
ERROR_COLOR = '#c0262d'


class MessageLog:
    """What the studio said: ``history`` (every line, oldest first) and the lines of the current action."""

    def __init__(self, shown: int = SHOWN, history: int = HISTORY) -> None:
        self.shown = shown
        self._keep = history
        self.history: list[str] = []
        self._current: list[str] = []

    def say(self, text: str) -> None:
        """Add a line to the current action's lines."""
        self.history.append(text)
        del self.history[:-self._keep]
        self._current.append(text)
        del self._current[:-self.shown]

    def begin(self, text: str) -> None:
        """A new action starts: the earlier lines (errors included) leave the box, ``text`` is its first line."""
        self._current = []
        self.say(text)

    def lines(self) -> list[str]:
        """The lines in the box, newest first."""
        return list(reversed(self._current))


def is_error(line: str) -> bool:
    """Whether a line reports a failure (drawn red)."""
    return ERROR_WORDS.search(line) is not None


def log_html(lines: list[str], shown: int = SHOWN) -> str:
    """The box: ``lines`` (newest first) in a block of fixed height (``shown`` lines, the rest scrolls), so that
    nothing below it moves when lines come and go."""
    rows = ''.join(f'<div style="color:{ERROR_COLOR}">{html.escape(t)}</div>' if is_error(t)
                   else f'<div>{html.escape(t)}</div>' for t in lines)
    return (f'<div class="studio-log" style="height:{shown * LINE_HEIGHT:.2f}em;overflow-y:auto;'
            f'line-height:{LINE_HEIGHT}em;font-size:0.85em;border:1px solid #ccc;border-radius:4px;'
            f'padding:0 0.4em;box-sizing:content-box">{rows}</div>')
