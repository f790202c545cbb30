"""The glue dispenser on a digital output, and the bead it lays: pure model, numpy only, explicit time.

**Flow.** The dispenser is switched by one digital output (``pin``; default 16, the first tool output). When
the control cycle at time t sees the output change, the valve follows after the switching delay
(``on_delay`` when it turns on, ``off_delay`` when it turns off): at that moment the flow's target becomes
``flow_rate`` or 0, and the flow q [m^3/s] follows it to first order,

    dq/dt = (q_target - q) / tau,        tau = time_constant,

integrated exactly between cycles (the volume of a cycle is the exact integral of q). A later command
cancels any valve change scheduled after its own (an off pulse shorter than on_delay - off_delay never
opens the valve). Once the output is off, no change is pending and q < ``IDLE_FLOW`` x flow_rate, the
dispenser is idle and q is set to 0 (the rest, < 0.1 % of the rate for tau, is not modelled).

Default ``time_constant`` 0.05 s, our estimate for a gun fed with urethane through a hose: the material is
viscous and slightly compressible and the hose elastic, so pressure at the nozzle builds up (and relaxes)
over tens of milliseconds after the gun's valve opens; 3 tau = 0.15 s to 95 % is the order of the start-up
blobs and thin starts that robot dispensing cells compensate with lead times. Defaults of the delays: 0.05 s
on (solenoid and valve opening), 0.03 s off.

**Deposit.** While material flows it lands where the nozzle axis meets the nearest surface (the ray cast is
the simulator's, ``controllers/dispenser.py``); with no surface within ``MAX_STANDOFF`` of the tip the
material is lost (counted in :attr:`BeadTrack.lost`). Along the track of that surface point (arc length s
[m], continuous within a *run* of deposition) the deposited volume V(s) is cumulative; the material of a
cycle is spread evenly over the cycle's stretch of track, so the cross-section area is

    A = dV/ds = q / v,       v = the speed of the surface point (the tip's speed over the surface).

**Profile.** The bead is a triangle on its base (the shape a V-cut nozzle gives windshield urethane):
width w across the base, height h = ``ASPECT`` x w, area A = w h / 2, so w = sqrt(2 A / ASPECT).
``ASPECT`` = 1.2 (e.g. 10 mm base, 12 mm high, a common windshield bead).

**Blobs.** Where the tip slows down or stands still, A = q / v grows without bound, but material piles up
where it lands and spreads over at least its own width. So the section at a point is the mean over a window
of track as long as the bead is wide there (and at least the nozzle diameter d, the least length one
strand of material covers):

    A(s) = (V(s + L/2) - V(s - L/2)) / L,    L = max(w(s), d),    w(s) = sqrt(2 A(s) / ASPECT),

solved per point by a damped fixed-point iteration. At constant speed this is exactly q / v; a blob of
volume V_b laid at one spot (the tip standing still) comes out as ASPECT w^3 / 2 = V_b + (bead volume within
the window), i.e. a pile as long as it is wide, whose width grows only with the cube root of its volume.
Bead points are reported every ``POINT_SPACING`` of track and at the end of each run.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ur_sim_driver.description.bead import ASPECT, Bead
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.io_bank import N_DIGITAL

IDLE_FLOW = 1e-3  # share of flow_rate below which a dispenser switched off is idle
MAX_STANDOFF = 0.05  # [m] farther than this from the tip along the nozzle axis, no surface catches the material
POINT_SPACING = 0.001  # [m] of track between reported bead points
MAX_JUMP = 0.02  # [m] a surface point moving farther in one cycle starts a new run (the ray jumped to another surface)
_ITERATIONS = 40  # of the width's fixed point; each halves the log error, 40 leave < 1e-12 relative
_RUN_SEPARATION = 100.0  # [m] runs are laid out this far apart on one track axis, so windows never join them


@dataclass(frozen=True)
class DispenserParams:
    """Dispenser settings, in the units of the ``dispenser.*`` parameters.

    Attributes:
        pin: digital output (0-17) that switches the dispenser; 16 and 17 are the tool outputs.
        flow_rate: [ml/s] steady flow while on.
        nozzle_diameter: [mm] of the nozzle's orifice.
        on_delay, off_delay: [s] from the output's change to the valve's.
        time_constant: [s] of the flow's first-order rise and fall after the valve's change.
    """

    pin: int = 16
    flow_rate: float = 6.0
    nozzle_diameter: float = 6.0
    on_delay: float = 0.05
    off_delay: float = 0.03
    time_constant: float = 0.05

    def __post_init__(self) -> None:
        if isinstance(self.pin, bool) or not isinstance(self.pin, (int, np.integer)) or \
                not 0 <= self.pin < N_DIGITAL:
            raise ConfigError(f"parameter 'dispenser.pin' = {self.pin!r} is not a digital output pin "
                              f'0..{N_DIGITAL - 1}')
        for name, lo, hi, open_lo in (('flow_rate', 0.0, 1000.0, True), ('nozzle_diameter', 0.0, 50.0, True),
                                      ('on_delay', 0.0, 10.0, False), ('off_delay', 0.0, 10.0, False),
                                      ('time_constant', 0.0, 10.0, False)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ConfigError(f"parameter 'dispenser.{name}' = {value!r} is not a number")
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and \
                (value > lo if open_lo else value >= lo) and value <= hi
            if not ok:
                raise ConfigError(f"parameter 'dispenser.{name}' = {value!r} is outside the allowed range "
                                  f"{'(' if open_lo else '['}{lo}, {hi}]")

    @property
    def rate(self) -> float:
        """Steady flow [m^3/s]."""
        return self.flow_rate * 1e-6

    @property
    def nozzle(self) -> float:
        """Nozzle diameter [m]."""
        return self.nozzle_diameter * 1e-3


# ---- flow ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class FlowState:
    """The dispenser at time ``t`` [s]: the output as last seen, the valve's target (0 or 1, a share of the
    rate), the flow as a share of the rate, and valve changes still to come ((time [s], target), in order)."""

    t: float = 0.0
    output: bool = False
    target: float = 0.0
    flow: float = 0.0
    pending: tuple[tuple[float, float], ...] = ()

    @property
    def idle(self) -> bool:
        """Off, nothing pending and no flow: nothing to simulate."""
        return not self.output and not self.pending and self.flow == 0.0 and self.target == 0.0


def _relax(flow: float, target: float, dt: float, tau: float) -> tuple[float, float]:
    """Flow share after ``dt`` and its integral over ``dt`` [s], first order towards ``target``."""
    if tau <= 0.0:
        return target, target * dt
    decay = math.exp(-dt / tau)
    return target + (flow - target) * decay, target * dt + (flow - target) * tau * (1.0 - decay)


def flow_step(p: DispenserParams, s: FlowState, t: float, output: bool) -> tuple[FlowState, float]:
    """Advance from ``s.t`` to ``t`` with what was commanded up to ``s.t``, then see ``output`` at ``t``.

    Returns:
        The state at ``t`` and the volume [m^3] that left the nozzle during [s.t, t].
    """
    now, flow, target, share = s.t, s.flow, s.target, 0.0
    pending = list(s.pending)
    while pending and pending[0][0] <= t:
        when, new_target = pending.pop(0)
        if when > now:
            flow, part = _relax(flow, target, when - now, p.time_constant)
            share += part
            now = when
        target = new_target
    if t > now:
        flow, part = _relax(flow, target, t - now, p.time_constant)
        share += part
    if output != s.output:
        when = t + (p.on_delay if output else p.off_delay)
        pending = [e for e in pending if e[0] <= when]  # the later command wins
        if when <= t:
            target, pending = (1.0 if output else 0.0), []
        else:
            pending.append((when, 1.0 if output else 0.0))
    if p.time_constant <= 0.0:
        flow = target  # no lag: the flow is the valve's target at once
    if not output and not pending and target == 0.0 and flow < IDLE_FLOW:
        flow = 0.0
    return replace(s, t=t, output=output, target=target, flow=flow, pending=tuple(pending)), share * p.rate


# ---- deposit ---------------------------------------------------------------------------------------------
class BeadTrack:
    """The deposit so far: samples of (track position s [m], cumulative volume V [m^3], surface point,
    time) per control cycle while material flows, grouped in runs, plus the lost volume. Grows in place
    (amortised O(1) per cycle); :meth:`bead` evaluates the bead from it, vectorised."""

    def __init__(self, nozzle_diameter: float) -> None:
        """``nozzle_diameter`` [m] is the least window length of the section (see the module docstring)."""
        self.nozzle = nozzle_diameter
        self._n = 0
        self._s = np.zeros(1024)
        self._v = np.zeros(1024)
        self._p = np.zeros((1024, 3))
        self._t = np.zeros(1024)
        self._run = np.zeros(1024, dtype=np.int64)
        self._runs = 0
        self._open = False  # whether the next deposit continues the last run
        self._start: tuple[np.ndarray, float] | None = None  # the last point seen while nothing flowed
        self.deposited = 0.0  # [m^3]
        self.lost = 0.0  # [m^3] that found no surface

    def __len__(self) -> int:
        return self._n

    def _append(self, s: float, v: float, point: np.ndarray, t: float) -> None:
        if self._n == len(self._s):
            grow = len(self._s)
            self._s, self._v, self._t = (np.concatenate([a, np.zeros(grow)]) for a in (self._s, self._v, self._t))
            self._p = np.concatenate([self._p, np.zeros((grow, 3))])
            self._run = np.concatenate([self._run, np.zeros(grow, dtype=np.int64)])
        i = self._n
        self._s[i], self._v[i], self._p[i], self._t[i], self._run[i] = s, v, point, t, self._runs - 1
        self._n += 1

    def add(self, t: float, point: np.ndarray | None, volume: float) -> None:
        """Material ``volume`` [m^3] that left the nozzle during the cycle ending at ``t`` [s], landing on the
        way to ``point`` (3,) [m] (None: no surface within reach: lost, and the run ends).

        A run starts with the first material: at the point of the cycle before (when given with no volume,
        as the simulator does from the cycle the output is seen on) or else at ``point`` itself.
        """
        if point is None:
            self.lost += volume
            self._open, self._start = False, None
            return
        point = np.asarray(point, dtype=float)
        n = self._n
        if self._open and float(np.linalg.norm(point - self._p[n - 1])) <= MAX_JUMP:
            s = self._s[n - 1] + float(np.linalg.norm(point - self._p[n - 1]))
            self._append(s, self._v[n - 1] + volume, point, t)
        elif volume <= 0.0:  # nothing flows yet: where the tip was, in case the next cycle's material starts there
            self._start = (point, t)
            return
        else:  # a new run, from where the tip was in the last cycle without material if that is near
            s = self._runs * _RUN_SEPARATION
            self._runs += 1
            start = self._start
            if start is not None and float(np.linalg.norm(point - start[0])) <= MAX_JUMP:
                self._append(s, self.deposited, start[0], start[1])
                s += float(np.linalg.norm(point - start[0]))
            else:  # the cycle's material lands at the first point
                self._append(s, self.deposited, point, t)
            self._append(s, self.deposited + volume, point, t)
            self._open = True
        self._start = None
        self.deposited += volume

    def end_run(self) -> None:
        """The flow has stopped: the next deposit starts a new run."""
        self._open, self._start = False, None

    def bead(self) -> Bead:
        """The bead laid so far: points every ``POINT_SPACING`` of track and at each run's end."""
        n = self._n
        if n == 0:
            return Bead.empty()
        s, v, p, t, run = self._s[:n], self._v[:n], self._p[:n], self._t[:n], self._run[:n]
        starts = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
        ends = np.r_[starts[1:], n] - 1
        # Query positions: every POINT_SPACING from each run's start, plus its end.
        lengths = s[ends] - s[starts]
        counts = np.floor(lengths / POINT_SPACING + 1e-9).astype(np.int64) + 1
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        q = np.repeat(s[starts], counts) + offsets * POINT_SPACING
        last_on_grid = np.isclose(q[np.cumsum(counts) - 1], s[ends], rtol=0.0, atol=1e-9)
        q = np.insert(q, np.cumsum(counts)[~last_on_grid], s[ends][~last_on_grid])
        points = np.stack([_interp(q, s, p[:, k], right=False) for k in range(3)], axis=1)
        times = _interp(q, s, t, right=False)
        w = _widths(q, s, v, self.nozzle)
        return Bead(points, w, ASPECT * w, times)


def _interp(x: np.ndarray, xp: np.ndarray, fp: np.ndarray, right: bool) -> np.ndarray:
    """Piecewise-linear fp(x) over non-decreasing ``xp`` with repeated knots (jumps): at a repeated knot the
    last value (``right``, the right limit) or the first (the left limit); clamped beyond the ends."""
    j = np.searchsorted(xp, x, side='right' if right else 'left')
    j = np.clip(j, 1, len(xp) - 1) if len(xp) > 1 else np.zeros_like(j)
    i = np.maximum(j - 1, 0)
    span = xp[j] - xp[i]
    frac = np.where(span > 0.0, (x - xp[i]) / np.where(span > 0.0, span, 1.0), 1.0 if right else 0.0)
    frac = np.clip(frac, 0.0, 1.0)
    if fp.ndim > 1:
        frac = frac[:, None]
    return fp[i] + (fp[j] - fp[i]) * frac


def _widths(q: np.ndarray, s: np.ndarray, v: np.ndarray, nozzle: float) -> np.ndarray:
    """Bead width [m] at track positions ``q``: the fixed point of w = sqrt(2 A / ASPECT) with A the mean
    section over the window L = max(w, nozzle) centred there (module docstring)."""
    w = np.full(len(q), nozzle)
    for _ in range(_ITERATIONS):
        window = np.maximum(w, nozzle)
        dv = _interp(q + window / 2, s, v, right=True) - _interp(q - window / 2, s, v, right=False)
        g = np.sqrt(2.0 * np.maximum(dv, 0.0) / (ASPECT * window))
        w = np.sqrt(w * g)  # damped: a blob's fixed point is approached from both sides
    return w


def dispenser_params(params: dict) -> DispenserParams:
    """DispenserParams from the flat ``dispenser.*`` entries of ``params`` (others are ignored).

    Raises:
        ConfigError: an unknown ``dispenser.*`` key (naming the valid ones) or a bad value.
    """
    fields = DispenserParams.__dataclass_fields__
    given = {k.split('.', 1)[1]: v for k, v in params.items() if k.startswith('dispenser.')}
    unknown = sorted(set(given) - set(fields))
    if unknown:
        raise ConfigError(f"parameter 'dispenser.{unknown[0]}' is unknown; valid names: "
                          f"{', '.join('dispenser.' + f for f in fields)}")
    # YAML and ROS give whole numbers as integers: keep the floats floats.
    given = {k: float(v) if k != 'pin' and isinstance(v, int) and not isinstance(v, bool) else v
             for k, v in given.items()}
    return DispenserParams(**given)
