"""The robot's safety checks that end in a protective stop, without ROS or MuJoCo.

A real UR enters PROTECTIVE_STOP when its safety system sees a collision (the joint torques differ from the
model's, or the TCP force exceeds its limit) or a joint position limit would be violated. ur_sim has the
contacts themselves, so it uses them (:class:`ContactSafety`): a contact of the arm or its tool with the scene
(floor, windshield) or with itself whose force, averaged over a window of :data:`DEFAULT_FORCE_WINDOW`
(parameter ``protective_stop_window``), exceeds :data:`DEFAULT_CONTACT_FORCE` (parameter
``protective_stop_force``); and a joint that the command drives into its position limit (the reference beyond
the limit while the joint is within :data:`LIMIT_MARGIN` of it). A trajectory that ends exactly at a limit is no
violation. Under torque control, where no command bounds the motion, a joint moving towards a limit that it could
not stop before (:func:`motion_limit_cause`).

The safety system acts on what it sees once armed: while the robot cannot move (a protective stop, powered off,
brakes engaged) it takes the contacts as they are, and once it can move again a contact present then stops the
robot only when it pushes :data:`FORCE_TOLERANCE` harder than it has since (the robot detects collisions as
torques the motion does not explain: an arm resting against something explains its torques). So an unlocked
protective stop does not stop again at once, the arm can be moved away, and a power cycle always clears it.

The figures: UR's manuals give the force limit a tolerance of 25 N (e-Series safety function table) and CB3's
TCP force limit a worst-case detection time of 250 ms (UR5 CB3 user manual 3.1, section 5.1); a 10 ms mean is
well within that, and smooths the first sample of a rigid contact, which no robot's safety system acts on. The
force limit is ours: UR's default collision sensitivity stops at roughly 100-150 N of TCP force, but the glass of
a windshield should not see that much; 50 N is about what a hand-guided nozzle pressed onto glass feels like.
Every figure here is documented in the README's parameter table.
"""
from __future__ import annotations

from collections import deque

import numpy as np
from numba import njit

from ur_sim_driver.physics.numba_types import B1, IN1
from ur_sim_driver.physics.physics import Contact

DEFAULT_CONTACT_FORCE = 50.0  # [N] contact force that triggers a protective stop
DEFAULT_FORCE_WINDOW = 0.01  # [s] the safety system's mean of the contact force
FORCE_TOLERANCE = 25.0  # [N] how much harder than when armed a contact present then must push to stop the robot
LIMIT_MARGIN = 1e-3  # [rad] a joint this close to a limit the reference lies beyond is "in" the limit
# [rad] a reference this little past a limit does not drive the joint into it: an arm braked to rest at its limit
# settles within microradians of it, on either side, and a controller that takes over holds where it is.
REFERENCE_TOLERANCE = 1e-4


class ContactSafety:
    """The protective stop from contact forces: a moving mean per pair of bodies, armed while the robot can move.

    Args:
        force_limit: [N] the mean contact force that stops the robot.
        window: number of control cycles the mean covers (>= 1).
        tolerance: [N] a contact present when the check was armed stops the robot only above
            max(force_limit, its lowest force since + tolerance).
    """

    def __init__(self, force_limit: float, window: int, tolerance: float = FORCE_TOLERANCE) -> None:
        self.force_limit = force_limit
        self.tolerance = tolerance
        self._history: deque[dict[tuple[str, str], Contact]] = deque(maxlen=max(1, window))
        self._tolerated: dict[tuple[str, str], float] = {}  # pair -> lowest mean force [N] since armed

    def filtered(self) -> dict[tuple[str, str], tuple[float, float]]:
        """Per pair of bodies (robot part, other): mean force [N] over the window and deepest penetration [m]."""
        n = self._history.maxlen
        out: dict[tuple[str, str], tuple[float, float]] = {}
        for cycle in self._history:
            for key, c in cycle.items():
                force, depth = out.get(key, (0.0, 0.0))
                out[key] = (force + c.force / n, max(depth, c.depth))
        return out

    def update(self, contacts: tuple[Contact, ...], armed: bool) -> str | None:
        """Take one control cycle's contacts; why they stop the robot now, or None. `armed`: the robot can move
        (RUNNING, NORMAL); while it cannot, the contacts as they are become the tolerated ones."""
        self._history.append({(c.robot_part, c.other): c for c in contacts})
        filtered = self.filtered() if any(self._history) else {}
        if not armed:
            self._tolerated = {key: force for key, (force, _) in filtered.items() if force > 0.0}
            return None
        cause = None
        over = [(force, key, depth) for key, (force, depth) in filtered.items() if force > self.limit_for(key)]
        if over:
            force, (part, other), depth = max(over)
            cause = (f'contact between {part} and {other}: force {force:.1f} N > {self.limit_for((part, other)):.1f} N '
                     f'(mean over {self._history.maxlen} cycles; penetration {depth * 1e3:.2f} mm)')
        for key in list(self._tolerated):
            force = filtered.get(key, (0.0, 0.0))[0]
            if force > 0.0:
                self._tolerated[key] = min(self._tolerated[key], force)
            else:
                del self._tolerated[key]  # the bodies parted: the next touch is a new contact
        return cause

    def limit_for(self, key: tuple[str, str]) -> float:
        """[N] the mean force at which the contact between the pair `key` stops the robot now."""
        tolerated = self._tolerated.get(key)
        return self.force_limit if tolerated is None else max(self.force_limit, tolerated + self.tolerance)


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
    upper = (reference > q_max + REFERENCE_TOLERANCE) & (q >= q_max - LIMIT_MARGIN)
    lower = (reference < q_min - REFERENCE_TOLERANCE) & (q <= q_min + LIMIT_MARGIN)
    hit = _first_hit(upper, lower, q_min, q_max)
    if hit is None:
        return None
    i, limit = hit
    return (f'{joint_names[i]} driven into its position limit {limit:.4f} rad (position {q[i]:.4f} rad, '
            f'commanded {reference[i]:.4f} rad)')


def motion_limit_cause(q: np.ndarray, qd: np.ndarray, q_min: np.ndarray, q_max: np.ndarray, a_stop: np.ndarray,
                       joint_names: tuple[str, ...]) -> str | None:
    """Why the safety system stops a robot under torque control, or None: a joint moving towards a position limit
    that it could not stop before when braking at `a_stop`. (No joint runs faster than its speed limit: the drives
    do not drive it past it, as under position control.)

    Args:
        q, qd: (n,) measured positions [rad] and velocities [rad/s].
        q_min, q_max: (n,) position limits [rad].
        a_stop: (n,) the deceleration the check assumes [rad/s^2] (below what the robot brakes with, so that the
            arm stops within the limit).
        joint_names: n names, for the message.
    """
    reach = q + qd * np.abs(qd) / (2.0 * a_stop)  # where each joint would stop
    hit = _first_hit((qd > 0.0) & (reach >= q_max), (qd < 0.0) & (reach <= q_min), q_min, q_max)
    if hit is None:
        return None
    i, limit = hit
    return (f'{joint_names[i]} would pass its position limit {limit:.4f} rad (position {q[i]:.4f} rad, '
            f'{qd[i]:.3f} rad/s)')


def _first_hit(upper: np.ndarray, lower: np.ndarray, q_min: np.ndarray, q_max: np.ndarray) -> tuple[int, float] | None:
    """The first joint flagged at its upper or lower limit, and that limit [rad]; None when none is."""
    hit = np.flatnonzero(upper | lower)
    if hit.size == 0:
        return None
    i = int(hit[0])
    return i, float(q_max[i] if upper[i] else q_min[i])


@njit(B1(IN1, IN1, IN1), cache=True)
def any_outside(x, lo, hi) -> bool:
    """Whether any x (n,) lies below lo (n,) or above hi (n,)."""
    for i in range(x.shape[0]):
        if x[i] < lo[i] or x[i] > hi[i]:
            return True
    return False

