"""Time law s(t) along the bead: constant tip speed with smooth ramps and local slowdowns.

The speed is piecewise constant in arc length ("levels"); between two levels, and from and
to rest at the path ends, it changes along a quintic smoothstep in time,
``sdot = v0 + (v1 - v0) S(tau)``, ``S = 10 tau^3 - 15 tau^4 + 6 tau^5``, so sdot is C2 and
s is C3. A change by dv lasts ``ramp_time * |dv| / speed``: every change has the same peak
tangential acceleration ``1.875 * speed / ramp_time`` [m/s^2] (0.5625 m/s^2 for 0.15 m/s
and 0.5 s). A change always happens inside the faster of the two stretches, so a slowdown
window is entered and left at its reduced speed.

The end ramps are lengthened by the same delta < dt so that the duration is a whole number
of samples: cruise speeds stay exact and the last sample is exactly at the end of the path.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ur_glue_planner.errors import PlanningError

_PEAK = 1.875  # max of the smoothstep's derivative S'(1/2)

#: ``usage(s, sdot, sddot) -> (K,)``: fraction of the tightest joint limit used at K path states.
Usage = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class SpeedLimit:
    """A stretch of the path [s_start, s_end] [m] where the speed is at most factor * speed."""

    s_start: float
    s_end: float
    factor: float


@dataclass(frozen=True, eq=False)
class PathTiming:
    """Sampled time law of a path; build it with :func:`time_path`.

    Attributes:
        length: Path length L [m].
        speed: Commanded cruise speed v [m/s].
        dt: Sample time [s].
        ramp_time: Duration [s] of a change between rest and v (end ramps: plus ``end_extra``).
        end_extra: Lengthening [s] of each end ramp that makes the duration a multiple of dt.
        duration: Total time [s].
        times: Sample times (M,) [s]; uniform dt, the last one equals ``duration``.
        s: Arc length (M,) [m]; s[0] = 0, s[-1] = L.
        sdot: Tip speed along the path (M,) [m/s].
        sddot: Tangential acceleration (M,) [m/s^2].
        levels: ((s_start, s_end, speed), ...) the constant-speed stretches [m], [m/s], after
            any slowdown; a change of level lies inside the faster neighbour.
        limits: The slowdown windows that were asked for.
        piece_t: Piece start times (P + 1,) [s].
        piece_s: Arc length (P,) [m] at each piece start.
        piece_v0: Speed (P,) [m/s] at each piece start.
        piece_v1: Speed (P,) [m/s] at each piece end (equal to v0 for a cruise piece).
    """

    length: float
    speed: float
    dt: float
    ramp_time: float
    end_extra: float
    duration: float
    times: np.ndarray
    s: np.ndarray
    sdot: np.ndarray
    sddot: np.ndarray
    levels: tuple[tuple[float, float, float], ...]
    limits: tuple[SpeedLimit, ...]
    piece_t: np.ndarray
    piece_s: np.ndarray
    piece_v0: np.ndarray
    piece_v1: np.ndarray

    @property
    def max_tangential_acceleration(self) -> float:
        """Largest |sddot| [m/s^2] of any speed change (attained at its middle)."""
        dur = np.diff(self.piece_t)
        dv = np.abs(self.piece_v1 - self.piece_v0)
        return float(np.max(_PEAK * dv / np.where(dur > 0, dur, np.inf), initial=0.0))

    def evaluate(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s [m], sdot [m/s], sddot [m/s^2] at times t [s] (scalar or (K,)), clamped to [0, T]."""
        tt = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), 0.0, self.duration)
        k = np.clip(np.searchsorted(self.piece_t, tt, side="right") - 1, 0, len(self.piece_s) - 1)
        dur = self.piece_t[k + 1] - self.piece_t[k]
        x = tt - self.piece_t[k]
        v0, dv = self.piece_v0[k], self.piece_v1[k] - self.piece_v0[k]
        tau = np.where(dur > 0, x / np.where(dur > 0, dur, 1.0), 0.0)
        step = tau ** 3 * (10.0 + tau * (-15.0 + 6.0 * tau))
        integral = tau ** 4 * (2.5 + tau * (-3.0 + tau))
        slope = 30.0 * tau ** 2 * (1.0 - tau) ** 2
        s = np.clip(self.piece_s[k] + v0 * x + dv * dur * integral, 0.0, self.length)
        sdot = v0 + dv * step
        sddot = np.where(dur > 0, dv * slope / np.where(dur > 0, dur, 1.0), 0.0)
        if np.ndim(t) == 0:
            return s[0], sdot[0], sddot[0]
        return s, sdot, sddot


def _initial_levels(length: float, speed: float, limits: Sequence[SpeedLimit]) -> list[list[float]]:
    cuts = {0.0, length}
    for lim in limits:
        cuts.update((min(max(lim.s_start, 0.0), length), min(max(lim.s_end, 0.0), length)))
    edges = sorted(cuts)
    levels: list[list[float]] = []
    for a, b in zip(edges[:-1], edges[1:]):
        if b - a <= 0.0:
            continue
        mid = 0.5 * (a + b)
        factor = min([lim.factor for lim in limits if lim.s_start <= mid <= lim.s_end], default=1.0)
        levels.append([a, b, speed * min(factor, 1.0)])
    return _merge(levels)


def _merge(levels: list[list[float]]) -> list[list[float]]:
    out = [levels[0]]
    for seg in levels[1:]:
        if abs(seg[2] - out[-1][2]) <= 1e-12 * max(1.0, seg[2]):
            out[-1][1] = seg[1]
        else:
            out.append(seg)
    return out


class _Layout:
    """Speed levels plus the peak tangential acceleration of each change between them.

    A change is keyed by the arc length of its level boundary (0 and L for the end ramps).
    """

    def __init__(self, levels: list[list[float]], a_nom: float, extra: float) -> None:
        self.levels, self.a_nom, self.extra = levels, a_nom, extra
        self.acc: dict[float, float] = {}

    def _changes(self, i: int) -> list[tuple[float, float, float]]:
        """(neighbour speed, s per m/s, extra time) of each change stretch i holds."""
        n, c = len(self.levels), self.levels[i][2]
        out = []
        for j, key in ((i - 1, self.levels[i][0]), (i + 1, self.levels[i][1])):
            end = not 0 <= j < n
            c_o = 0.0 if end else self.levels[j][2]
            if c_o < c:
                out.append((c_o, _PEAK / self.acc.get(key, self.a_nom), self.extra if end else 0.0))
        return out

    def fit(self) -> bool:
        """Lower levels until each stretch holds its changes to slower neighbours; True if any moved."""
        moved = False
        for _ in range(10 * len(self.levels) + 10):
            changed = False
            for i, (a, b, c) in enumerate(self.levels):
                changes = self._changes(i)
                need = sum(0.5 * (c + c_o) * (r * (c - c_o) + e) for c_o, r, e in changes)
                if need <= (b - a) * (1.0 + 1e-12):
                    continue
                # sum over changes of (c + c_o)/2 (r (c - c_o) + e) = b - a: a quadratic in c
                qa = 0.5 * sum(r for _, r, _ in changes)
                qb = 0.5 * sum(e for _, _, e in changes)
                qc = sum(0.5 * e * c_o - 0.5 * r * c_o * c_o for c_o, r, e in changes) - (b - a)
                self.levels[i][2] = (-qb + math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)
                changed = moved = True
            self.levels = _merge(self.levels)
            if not changed:
                return moved
        raise PlanningError("speed levels did not settle")  # pragma: no cover (monotone decrease)

    def pieces(self) -> list[tuple[float, float, float, float, float]]:
        """(duration, start s, start speed, end speed, boundary key) of each piece."""
        out = []
        n = len(self.levels)
        speeds = [0.0] + [lv[2] for lv in self.levels] + [0.0]
        for i, (a, b, c) in enumerate(self.levels):
            c_prev, c_next = speeds[i], speeds[i + 2]
            t_in = t_out = 0.0
            if c_prev < c:
                t_in = _PEAK * (c - c_prev) / self.acc.get(a, self.a_nom) + (self.extra if i == 0 else 0.0)
            if c_next < c:
                t_out = _PEAK * (c - c_next) / self.acc.get(b, self.a_nom) + (self.extra if i == n - 1 else 0.0)
            d_in, d_out = 0.5 * (c + c_prev) * t_in, 0.5 * (c + c_next) * t_out
            if t_in > 0.0:
                out.append((t_in, a, c_prev, c, a))
            cruise = max(b - a - d_in - d_out, 0.0)
            if cruise > 0.0:
                out.append((cruise / c, a + d_in, c, c, math.nan))
            if t_out > 0.0:
                out.append((t_out, b - d_out, c, c_next, b))
        return out

    def respect(self, usage: Usage | None, floor: float) -> bool:
        """Soften each speed change whose tangential acceleration overloads a joint; True if any did.

        Only overloads the change itself causes count (usage above both 1 and the usage at
        the same speed without acceleration); a speed that is too high is the levels' business.
        """
        if usage is None:
            return False
        changes = [p for p in self.pieces() if p[2] != p[3]]  # each has its own key
        if not changes:
            return False
        tau = np.linspace(0.0, 1.0, 33)
        step = tau ** 3 * (10.0 + tau * (-15.0 + 6.0 * tau))
        integral = tau ** 4 * (2.5 + tau * (-3.0 + tau))
        slope = 30.0 * tau ** 2 * (1.0 - tau) ** 2
        dur, s0, v0, v1 = (np.array([p[i] for p in changes])[:, None] for i in range(4))
        dv = v1 - v0
        s = (s0 + v0 * dur * tau + dv * dur * integral).ravel()
        sdot = (v0 + dv * step).ravel()
        # every change, with and without its acceleration, in one usage call
        full, base = usage(np.tile(s, 2), np.tile(sdot, 2),
                           np.concatenate([(dv * slope / dur).ravel(), np.zeros_like(s)])).reshape(2, len(changes), -1)
        worst = np.max(np.where(full > np.maximum(base, 1.0) + 1e-9, full, 0.0), axis=1)
        moved = False
        for (_, _, _, _, key), w in zip(changes, worst):
            if w > 0.0:
                current = self.acc.get(key, self.a_nom)
                self.acc[key] = max(current * min(0.8, 1.0 / float(w)), floor)
                moved = moved or self.acc[key] < current
        return moved


def time_path(length: float, speed: float, dt: float, ramp_time: float = 0.5,
              limits: Sequence[SpeedLimit] = (),
              usage: Usage | None = None) -> PathTiming:
    """Time a path of ``length`` for cruise ``speed``, starting and ending at rest.

    Args:
        length: Path length [m] (> 0).
        speed: Cruise speed [m/s] (> 0).
        dt: Sample time [s] (> 0).
        ramp_time: Duration [s] of the change from rest to ``speed`` where nothing else limits
            it (> 0): the peak tangential acceleration is ``1.875 * speed / ramp_time``. The
            end ramps get up to dt more. A path too short to reach ``speed`` gets a lower
            peak speed so that the ramps meet.
        limits: Stretches with a lower speed (slowdowns).
        usage: Optional ``usage(s, sdot, sddot) -> (K,)``: the largest fraction of any joint
            limit used at K path states (> 1 is too much). Every speed change, the end
            ramps included, is made gentle enough to keep it within 1 (or within what the
            same speed without acceleration uses); at most 1000 times longer than nominal.

    Raises:
        ValueError: A non-positive or non-finite argument, or a limit factor outside (0, 1].
    """
    for name, value in (("length", length), ("speed", speed), ("dt", dt), ("ramp_time", ramp_time)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} {value} must be finite and > 0")
    for lim in limits:
        if not 0.0 < lim.factor <= 1.0 or not lim.s_end >= lim.s_start:
            raise ValueError(f"slowdown {lim} needs 0 < factor <= 1 and s_end >= s_start")
    a_nom = _PEAK * speed / ramp_time
    floor = 1e-3 * a_nom  # a change may not take more than 1000 ramp times
    base = _initial_levels(length, speed, limits)

    def build(extra: float) -> tuple[_Layout, np.ndarray, list]:
        lay = _Layout([list(lv) for lv in base], a_nom, extra)
        for _ in range(200):
            moved = lay.fit()
            moved = lay.respect(usage, floor) or moved
            if not moved:
                break
        pieces = lay.pieces()
        return lay, np.concatenate([[0.0], np.cumsum([p[0] for p in pieces])]), pieces

    lay, piece_t, pieces = build(0.0)
    # longer end ramps add exactly their extra time (while the end stretches have room)
    extra = math.ceil(piece_t[-1] / dt - 1e-9) * dt - piece_t[-1]
    if extra > 1e-12:
        lay, piece_t, pieces = build(extra)
    duration = float(piece_t[-1])
    n = math.ceil(duration / dt - 1e-9)
    times = np.arange(n + 1) * dt
    times[-1] = duration  # equal up to rounding unless a speed change had to move
    if n >= 2 and times[-1] - times[-2] < 0.5 * dt:  # no sliver of a last interval
        times = np.delete(times, -2)
    timing = PathTiming(
        length=float(length), speed=float(speed), dt=float(dt), ramp_time=float(ramp_time),
        end_extra=float(extra), duration=duration, times=times,
        s=np.empty(0), sdot=np.empty(0), sddot=np.empty(0),
        levels=tuple((float(a), float(b), float(c)) for a, b, c in lay.levels), limits=tuple(limits),
        piece_t=piece_t, piece_s=np.array([p[1] for p in pieces]), piece_v0=np.array([p[2] for p in pieces]),
        piece_v1=np.array([p[3] for p in pieces]))
    s, sdot, sddot = timing.evaluate(times)
    s[-1] = length
    for name, arr in (("s", s), ("sdot", sdot), ("sddot", sddot)):
        object.__setattr__(timing, name, arr)
    return timing
