"""Joint states recorded as they arrive and resampled at a fixed rate of message (robot) time.

Pure: the client's spinning thread appends the samples (``URClient.start_recording``); resampling picks, for each
time on the grid, the newest message at or before it, as seed 2's scripts sample their recordings.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_glue_planner.errors import ClientError

# Two stamps this close [s] are the same time: a stamp is exact to the nanosecond, but as float seconds on the
# system clock (the real driver's, ur_sim's in real time; about 1.8e9 s) it resolves only about 0.24 us.
STAMP_TIE = 1e-6


@dataclass(frozen=True)
class JointStateSample:
    """One /joint_states message: stamp t [s], names, q [rad], qd [rad/s], effort [N m] (arrays (n,))."""

    t: float
    names: tuple[str, ...]
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray


@dataclass(frozen=True)
class Recording:
    """Joint states sampled at a fixed rate: t (K,) [s] from the first sample, q, qd, effort (K, n)."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray


class JointStateRecorder:
    """Joint states received while recording, resampled at a fixed rate of message time."""

    def __init__(self, rate: float, t0: float | None = None) -> None:
        self.rate = rate
        self.t0 = t0
        self.samples: list[JointStateSample] = []

    def start(self) -> float:
        """Time of sample 0 [s]: the given t0, else the first message's stamp."""
        return self.t0 if self.t0 is not None else self.samples[0].t

    def span(self) -> float:
        """Message time covered so far from the start [s]."""
        return self.samples[-1].t - self.start() if self.samples else 0.0

    def _taken(self) -> list[JointStateSample]:
        """The samples so far, copied once: the spinning thread may append one while they are read (stopped, a
        recorder can still get the message its thread was handing out), and t, q, qd and effort must agree."""
        samples = list(self.samples)
        if not samples:
            raise ClientError('no joint states were received while recording')
        return samples

    def raw(self) -> Recording:
        """Every message received, t relative to the start [s] (messages before the start included, t < 0)."""
        samples = self._taken()
        t0 = self.start()
        return Recording(np.array([s.t - t0 for s in samples]), np.array([s.q for s in samples]),
                         np.array([s.qd for s in samples]), np.array([s.effort for s in samples]))

    def resample(self, duration: float | None = None) -> Recording:
        """Samples at start + k / rate, k < duration x rate (the seed's N = tf x rate): for each, the newest
        message at or before that time."""
        samples = self._taken()
        stamps = np.array([s.t for s in samples])
        t0 = self.start()
        covered = int(np.floor((stamps[-1] - t0 + STAMP_TIE) * self.rate)) + 1
        if covered <= 0:
            raise ClientError(f'no joint states at or after the recording start t0 = {t0:.3f} s '
                              f'(newest stamp {stamps[-1]:.3f} s)')
        count = covered if duration is None else min(covered, round(duration * self.rate))
        grid = np.arange(count) / self.rate
        picks = np.maximum(np.searchsorted(stamps, t0 + grid + STAMP_TIE, side='right') - 1, 0)
        chosen = [samples[i] for i in picks]
        return Recording(grid, np.array([s.q for s in chosen]), np.array([s.qd for s in chosen]),
                         np.array([s.effort for s in chosen]))
