"""The robot's safety checks that end in a protective stop, without ROS or MuJoCo.

A real UR enters PROTECTIVE_STOP when its safety system sees a collision (the joint torques differ from the
model's, or the TCP force exceeds its limit) or a joint position limit would be violated. ur_sim has the
contacts themselves, so it uses them: any contact of the arm or its tool with the scene (floor, windshield) or
with itself whose force exceeds :data:`DEFAULT_CONTACT_FORCE` (parameter ``protective_stop_force``), and a
joint that the command drives into its position limit (the reference beyond the limit while the joint is
within :data:`LIMIT_MARGIN` of it). A trajectory that ends exactly at a limit is no violation.

The threshold is ours: UR's default collision sensitivity stops at roughly 100-150 N of TCP force, but the
glass of a windshield should not see that much; 50 N is about what a hand-guided nozzle pressed onto glass
feels like. Every figure here is documented in the README's safety section.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ur_sim_driver.numba_types import B1, IN1

DEFAULT_CONTACT_FORCE = 50.0  # [N] contact force that triggers a protective stop
LIMIT_MARGIN = 1e-3  # [rad] a joint this close to a limit the reference lies beyond is "in" the limit


@dataclass(frozen=True)
class Contact:
    """One contact the robot takes part in.

    Attributes:
        robot_part: the robot's body (link or tool) in contact.
        other: the other body, or the scene geom (e.g. 'floor') for bodies fixed to the world.
        force: magnitude of the contact force [N] (normal and friction).
        depth: penetration [m] (>= 0; MuJoCo's soft contacts let bodies overlap slightly).
    """

    robot_part: str
    other: str
    force: float
    depth: float


def contact_cause(contacts: tuple[Contact, ...], force_limit: float) -> str | None:
    """Why the contacts stop the robot (the strongest one above `force_limit` [N]), or None."""
    over = [c for c in contacts if c.force > force_limit]
    if not over:
        return None
    c = max(over, key=lambda c: c.force)
    return (f'contact between {c.robot_part} and {c.other}: force {c.force:.1f} N > {force_limit:.1f} N '
            f'(penetration {c.depth * 1e3:.2f} mm)')


def limit_cause(q: np.ndarray, reference: np.ndarray, q_min: np.ndarray, q_max: np.ndarray,
                joint_names: tuple[str, ...]) -> str | None:
    """Why the joints stop the robot (one driven into a position limit), or None.

    Args:
        q: (n,) measured positions [rad].
        reference: (n,) commanded positions [rad].
        q_min, q_max: (n,) position limits [rad].
        joint_names: n names, for the message.
    """
    # Commands within the limits, the case of every cycle, are ruled out by one compiled call.
    if not any_outside(reference, q_min, q_max):
        return None
    upper = (reference > q_max) & (q >= q_max - LIMIT_MARGIN)
    lower = (reference < q_min) & (q <= q_min + LIMIT_MARGIN)
    hit = np.flatnonzero(upper | lower)
    if hit.size == 0:
        return None
    i = int(hit[0])
    limit = q_max[i] if upper[i] else q_min[i]
    return (f'{joint_names[i]} driven into its position limit {limit:.4f} rad (position {q[i]:.4f} rad, '
            f'commanded {reference[i]:.4f} rad)')


@njit(B1(IN1, IN1, IN1), cache=True)
def any_outside(x, lo, hi) -> bool:
    """Whether any x (n,) lies below lo (n,) or above hi (n,)."""
    for i in range(x.shape[0]):
        if x[i] < lo[i] or x[i] > hi[i]:
            return True
    return False

