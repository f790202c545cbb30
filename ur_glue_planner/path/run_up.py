"""A closed bead walked with a flying start: from ``-run_up`` before its start to ``run_out`` past its end.

The glue gun only switches; it cannot follow the tip's speed. Where the tip accelerates from rest or stops,
a constant flow lays a blob. On a closed loop the tip can instead start on the loop's tail (dispenser off),
reach the commanded speed before the bead start, lay the whole loop at that speed, and slow down only after
the flow has stopped, past the closure. The run-out passes over the bead's first centimetres: the nozzle must
then stand off above the bead (see README, "The glue bead").
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ur_glue_planner.path.glue_path import GluePath


@dataclass(frozen=True, eq=False)
class RunUpPath:
    """The motion path of a bead with a flying start, in its own arc length x = s + run_up [m].

    It has the GluePath methods the planner's stages use (``sample``, ``position``, ``derivatives``,
    ``curvature_vector``, ``quaternion``, ``orientation``, ``length``, ``closed``, ``waypoint_s``); x in
    [0, length] maps to the loop's s modulo its length.

    Attributes:
        loop: The closed bead.
        run_up, run_out: [m] walked before the bead start and past its end.
    """

    loop: GluePath
    run_up: float
    run_out: float

    def __post_init__(self) -> None:
        if not self.loop.closed:
            raise ValueError("a flying start needs a closed bead")
        if self.run_up < 0.0 or self.run_out < 0.0 or self.run_up + self.run_out >= self.loop.length:
            raise ValueError(f"run_up {self.run_up:.4f} m and run_out {self.run_out:.4f} m must be >= 0 and "
                             f"together shorter than the loop ({self.loop.length:.4f} m)")

    closed = False  # the motion itself has two ends

    @property
    def length(self) -> float:
        return self.loop.length + self.run_up + self.run_out

    @property
    def waypoint_s(self) -> np.ndarray:
        return self.loop.waypoint_s + self.run_up

    def _loop_s(self, x: np.ndarray | float) -> np.ndarray:
        return np.asarray(x, dtype=float) - self.run_up

    def sample(self, x: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.loop.sample(self._loop_s(x))

    def curvature_vector(self, x: np.ndarray | float) -> np.ndarray:
        return self.loop.curvature_vector(self._loop_s(x))

    def position(self, x: np.ndarray | float) -> np.ndarray:
        return self.loop.position(self._loop_s(x))

    def derivatives(self, x: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.loop.derivatives(self._loop_s(x))

    def quaternion(self, x: np.ndarray | float) -> np.ndarray:
        return self.loop.quaternion(self._loop_s(x))

    def orientation(self, x: np.ndarray | float) -> np.ndarray:
        return self.loop.orientation(self._loop_s(x))
