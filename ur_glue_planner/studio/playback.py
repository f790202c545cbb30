"""Playing a plan on the robot model: one timeline over its segments, a play/pause/scrub/speed clock, and the
bead's colours by planned tip speed."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from matplotlib import colormaps

from ur_glue_planner.motion.plan import GluePlan

SPEED_COLORMAP = 'viridis'


@dataclass(frozen=True, eq=False)
class Timeline:
    """The plan's segments end to end: times t (N,) [s] from 0, joint positions q (N, n) [rad], tip positions
    tip (N, 3) [m], segment name per sample, and each segment's (name, start, end) [s]."""

    t: np.ndarray
    q: np.ndarray
    tip: np.ndarray
    segment: tuple[str, ...]
    spans: tuple[tuple[str, float, float], ...]

    @classmethod
    def from_plan(cls, plan: GluePlan) -> Timeline:
        ts, qs, tips, names, spans = [], [], [], [], []
        offset = 0.0
        kin = plan.kinematics
        for seg in plan.segments():
            times = np.asarray(seg.times) + offset
            if ts:  # segments join: drop a repeated first sample
                times, q = times[1:], seg.q[1:]
            else:
                q = seg.q
            tip = plan.bead.tip_pos[-len(q):] if seg.name == 'bead' else np.array([kin.fk(x)[:3, 3] for x in q])
            ts.append(times)
            qs.append(q)
            tips.append(tip)
            names += [seg.name] * len(times)
            spans.append((seg.name, offset, offset + seg.duration))
            offset += seg.duration
        return cls(np.concatenate(ts), np.vstack(qs), np.vstack(tips), tuple(names), tuple(spans))

    @property
    def duration(self) -> float:
        """[s]."""
        return float(self.t[-1])

    def q_at(self, t: float) -> np.ndarray:
        """Joint positions (n,) [rad] at time t [s] (linear between samples, clamped to the ends)."""
        return np.array([np.interp(t, self.t, self.q[:, j]) for j in range(self.q.shape[1])])

    def tip_until(self, t: float) -> np.ndarray:
        """Tip positions (K, 3) [m] of the samples up to t [s]."""
        return self.tip[: int(np.searchsorted(self.t, t, side='right'))]

    def segment_at(self, t: float) -> str:
        """Name of the segment running at t [s]."""
        return next((name for name, a, b in self.spans if a <= t <= b), self.spans[-1][0])


@dataclass(frozen=True)
class Clock:
    """Playback clock: time t [s] in [0, duration], playing or paused, speed factor (wall seconds -> plan seconds)."""

    duration: float
    t: float = 0.0
    playing: bool = False
    speed: float = 1.0

    def advance(self, wall_dt: float) -> Clock:
        """After ``wall_dt`` [s] of wall time; stops at the end."""
        if not self.playing:
            return self
        t = self.t + wall_dt * self.speed
        return dataclasses.replace(self, t=min(t, self.duration), playing=t < self.duration)

    def play(self) -> Clock:
        """Play (from the start if at the end)."""
        return dataclasses.replace(self, playing=True, t=0.0 if self.t >= self.duration else self.t)

    def pause(self) -> Clock:
        return dataclasses.replace(self, playing=False)

    def seek(self, t: float) -> Clock:
        """Jump to t [s] (clamped)."""
        return dataclasses.replace(self, t=float(np.clip(t, 0.0, self.duration)))

    def with_speed(self, speed: float) -> Clock:
        """Playback speed factor in [0.05, 10]."""
        if not 0.05 <= speed <= 10.0:
            raise ValueError(f'playback speed {speed!r} is not in [0.05, 10]')
        return dataclasses.replace(self, speed=float(speed))


def speed_colors(speed: np.ndarray, v_max: float) -> np.ndarray:
    """RGB colours (N, 3) in [0, 1] of tip speeds (N,) [m/s] on the speed colormap over [0, v_max]."""
    x = np.clip(np.asarray(speed, dtype=float) / max(v_max, 1e-9), 0.0, 1.0)
    return colormaps[SPEED_COLORMAP](x)[:, :3]


def bead_segments(plan: GluePlan, v_max: float | None = None, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """The planned bead as line segments (M, 2, 3) [m] and their colours (M, 2, 3) by planned tip speed.

    ``v_max`` [m/s] tops the colour scale (default: 1.1 x the commanded speed).
    """
    tip = plan.bead.tip_pos[::stride]
    speed = plan.bead.tcp_speed[::stride]
    colors = speed_colors(speed, v_max or 1.1 * plan.job.tcp_speed)
    return np.stack([tip[:-1], tip[1:]], axis=1), np.stack([colors[:-1], colors[1:]], axis=1)
