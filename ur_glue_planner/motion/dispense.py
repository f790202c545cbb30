"""When to switch the glue gun: the set_io times that put material on the glass from the bead start to its end.

The gun (ur_sim's model, and a real gun to first order) answers its output with a dead time and a first-order
flow: material leaves the nozzle ``on_delay`` after the output goes on and rises to the set rate as
``1 - exp(-t / time_constant)``; after the output goes off it flows on for ``off_delay`` and then falls as
``exp(-t / time_constant)``. A first-order rise lays the same amount of material as a step ``time_constant``
later, and a fall the same as a step ``time_constant`` later, so the planner switches

    on  at  t_arrive - (on_delay + time_constant)     lead = on_delay + time_constant
    off at  t_leave  - (off_delay + time_constant)    lag  = off_delay + time_constant

where ``t_arrive`` and ``t_leave`` are the trajectory times at which the tip passes the bead start and end
(from the timed path). On a closed loop the start's rise and the end's fall then lie on the same stretch of
glass and add up to the full bead (a crossfade) instead of a gap or a blob. Times are trajectory time of the
bead segment (``time_from_start``), which the executor maps onto the controller's scaled clock.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.job import DispenserSpec


@dataclass(frozen=True)
class DispenseSchedule:
    """The dispenser's switching on the bead segment (times [s] in its trajectory time, lengths [m]).

    Attributes:
        pin: SetIO digital output pin.
        s_start, s_end: Arc length of the bead segment's motion where material should start and stop.
        t_arrive, t_leave: When the tip passes s_start and s_end.
        t_on, t_off: When to call set_io (state 1, then 0); t_on may be negative (before the segment starts).
        lead: t_arrive - t_on. lag: t_leave - t_off.
        speed_start, speed_end: Planned tip speed [m/s] at s_start and s_end.
        flow_rate: [ml/s]. nominal_area: flow_rate / commanded speed [mm^2], the bead's cross-section.
    """

    pin: int
    s_start: float
    s_end: float
    t_arrive: float
    t_leave: float
    t_on: float
    t_off: float
    lead: float
    lag: float
    speed_start: float
    speed_end: float
    flow_rate: float
    nominal_area: float

    def as_dict(self) -> dict:
        """For summary.json."""
        return {k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in self.__dict__.items()}


def time_at(times: np.ndarray, s: np.ndarray, s_target: float) -> float:
    """First time [s] at which the sampled arc length s (M,) (non-decreasing) reaches ``s_target`` [m],
    linear between samples."""
    times, s = np.asarray(times, dtype=float), np.asarray(s, dtype=float)
    if s_target <= s[0]:
        return float(times[0])
    if s_target > s[-1] + 1e-9:
        raise PlanningError(f"dispenser: the bead ends at s = {s[-1]:.4f} m before s = {s_target:.4f} m")
    k = int(np.searchsorted(s, s_target, side="left"))
    k = min(max(k, 1), len(s) - 1)
    ds = s[k] - s[k - 1]
    frac = 0.0 if ds <= 0.0 else (s_target - s[k - 1]) / ds
    return float(times[k - 1] + frac * (times[k] - times[k - 1]))


def schedule_dispenser(spec: DispenserSpec, times: np.ndarray, s: np.ndarray, speed: np.ndarray, s_start: float,
                       s_end: float, tcp_speed: float) -> DispenseSchedule:
    """Switch times for material on [s_start, s_end] of a bead segment timed as (times, s, speed) (M,).

    Args:
        spec: The gun (pin, delays, time constant, flow).
        times, s, speed: Sample times [s], arc length [m] and tip speed [m/s] of the segment's motion.
        s_start, s_end: Where material should start and stop [m], 0 <= s_start < s_end <= s[-1].
        tcp_speed: Commanded tip speed [m/s] (for the nominal cross-section).
    """
    if not 0.0 <= s_start < s_end:
        raise PlanningError(f"dispenser: bead from s = {s_start:.4f} m to {s_end:.4f} m is empty")
    t_arrive, t_leave = time_at(times, s, s_start), time_at(times, s, s_end)
    lead = spec.on_delay + spec.time_constant
    lag = spec.off_delay + spec.time_constant
    t_on, t_off = t_arrive - lead, t_leave - lag
    if t_off <= t_on:
        raise PlanningError(f"dispenser: the bead lasts {t_leave - t_arrive:.3f} s, shorter than the gun's "
                            f"switching (lead {lead:.3f} s, lag {lag:.3f} s)")
    v = np.interp([s_start, s_end], s, speed)
    return DispenseSchedule(pin=spec.pin, s_start=float(s_start), s_end=float(s_end), t_arrive=t_arrive,
                            t_leave=t_leave, t_on=t_on, t_off=t_off, lead=lead, lag=lag,
                            speed_start=float(v[0]), speed_end=float(v[1]), flow_rate=spec.flow_rate,
                            nominal_area=spec.flow_rate * 1e-6 / tcp_speed * 1e6)


def run_up_length(spec: DispenserSpec, tcp_speed: float, ramp_time: float, margin: float = 0.005) -> float:
    """Run-up (= run-out) [m] of a flying start: the start ramp's length (v T / 2), four time constants of
    flow rise or fall at cruise speed (the flow is then within 2 % of its end value), and ``margin`` [m]."""
    return tcp_speed * (0.5 * ramp_time + 4.0 * spec.time_constant) + margin
