"""Whether a robot type can reach a bead at all: the arm's outer envelope against the farthest flange position.

Seen from the shoulder (the base frame's origin raised by d1), a UR arm's flange lies at ``P + d5 u + d6 w``
plus ``d4 z``: z is the axis of joints 2 to 4, P the two tubes (|P| <= |a2| + |a3|) and u the wrist-2 axis, both
in the plane normal to z, and w the wrist-3 axis, normal to u, at an angle t to z. The largest distance is
therefore ``max over t of sqrt((|a2| + |a3| + sqrt(d5^2 + d6^2 sin^2 t))^2 + (d4 + d6 cos t)^2)``, reached with
the arm stretched; a flange position beyond it is out of every IK branch's reach. The check runs before IK so
that a job on a type too small for the part is refused with the reason, not with an IK failure at some sample; it
is generous (the data sheet's reach is shorter), and IK has the last word.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from ur_sim_driver.description.params import URParams
from ur_sim_driver.description.tool import ToolDef


def envelope(robot: URParams) -> float:
    """Largest distance [m] of the flange (tool0) from the shoulder over all joint positions (see above)."""
    d = robot.dh

    def minus_distance(t: float) -> float:
        return -math.hypot(abs(d.a2) + abs(d.a3) + math.hypot(d.d5, d.d6 * math.sin(t)), d.d4 + d.d6 * math.cos(t))

    coarse = min(np.linspace(0.0, math.pi, 181), key=minus_distance)  # one hump on [0, pi]: bracket it, refine
    best = minimize_scalar(minus_distance, bounds=(max(0.0, coarse - 0.02), min(math.pi, coarse + 0.02)),
                           method='bounded', options={'xatol': 1e-12})
    return -float(best.fun)


def flange_positions(points: np.ndarray, rotations: np.ndarray, tool: ToolDef | None) -> np.ndarray:
    """Flange (tool0) positions (K, 3) [m] for tip positions (K, 3) [m] and tip rotations (K, 3, 3)."""
    if tool is None:
        return np.asarray(points, dtype=float)
    tip = tool.tip_in_tool0()
    offset = tip[:3, :3].T @ tip[:3, 3]  # the tip's position in tool0, in tip axes
    return np.asarray(points, dtype=float) - np.einsum('kij,j->ki', rotations, offset)


def reach_refusal(points: np.ndarray, rotations: np.ndarray, robot: URParams, tool: ToolDef | None) -> str | None:
    """Why `robot` cannot reach the bead through tip poses (points (K, 3) [m], rotations (K, 3, 3), base frame),
    or None when every flange position lies within its envelope."""
    shoulder = np.array([0.0, 0.0, robot.dh.d1])
    distance = np.linalg.norm(flange_positions(points, rotations, tool) - shoulder, axis=1)
    k, limit = int(np.argmax(distance)), envelope(robot)
    if distance[k] <= limit:
        return None
    return (f"ur_type {robot.name!r} cannot reach the bead: its flange is never more than {limit:.3f} m from its "
            f"shoulder (data-sheet reach {robot.reach:.3f} m), but must be {distance[k]:.3f} m away at waypoint {k} "
            f"{np.round(points[k], 4).tolist()}; choose a type with a longer reach or place the part closer")
