"""Choice of the arm configuration (IK branch) in which the whole bead is laid.

A 6R arm reaches a pose in up to eight ways (shoulder left/right, elbow up/down, wrist
flipped or not); warm-started IK then stays in the branch it starts in. Not every branch
can follow the whole bead: for the seed's windshield, only the branches with the wrist flipped
(q5 > 0 in the ROS 2 description) reach the top edge, and IK from the home pose lands in one
of the others for some start points (the seed's first waypoint). So the planner collects the
branches at the bead start (IK from the reference pose, then for a UR arm its eight closed-form
solutions, for other kinematics fixed pseudo-random guesses), follows each one along the bead on
a coarse grid (a UR arm: its closed-form branch, all grid points at once), and keeps the branch
that stays continuous, clear of itself and the floor (``clearance.py``), with the lowest peak joint-speed demand
(furthest from singularities); near-ties go to the branch nearest to the reference pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.motion.clearance import Clearance
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.motion.ur_arm_kinematics import UrKinematics
from ur_glue_planner.path.glue_path import GluePath
from ur_sim_driver.description.analytic_ik import follow_branch, nearest_branch

_TWO_PI = 2.0 * math.pi
_SPACING = 0.02  # [m] grid on which a branch is followed along the bead
_MAX_JUMP = 0.6  # [rad] a larger joint step between grid points is a change of branch


@dataclass(frozen=True)
class Branch:
    """One IK branch at the bead start.

    Attributes:
        q: Joint positions (n,) [rad] at the bead start, each joint taken within 2 pi of the
            reference where the limits allow.
        feasible: It follows the whole bead without IK failure or jump.
        peak_usage: Largest |dq/ds| * speed / v_max of any joint along the bead (inf if not
            feasible); > 1 means the bead needs a slowdown in this branch.
        distance: Euclidean norm of q - reference [rad] at the bead start.
        reason: Why it is not feasible ('' if it is).
    """

    q: np.ndarray
    feasible: bool
    peak_usage: float
    distance: float
    reason: str


def _near(q: np.ndarray, reference: np.ndarray, q_min: np.ndarray, q_max: np.ndarray) -> np.ndarray:
    """q with each joint shifted by whole turns towards the reference, staying within limits."""
    cands = q[:, None] + _TWO_PI * np.arange(-2, 3)  # (n, 5)
    inside = (cands >= q_min[:, None]) & (cands <= q_max[:, None])
    gap = np.where(inside, np.abs(cands - reference[:, None]), np.inf)
    best = cands[np.arange(len(q)), np.argmin(gap, axis=1)]
    return np.where(inside.any(axis=1), best, q)


def start_branches(kin: Kinematics, target: np.ndarray, reference: np.ndarray, n_random: int = 32,
                   seed: int = 0) -> list[np.ndarray]:
    """Distinct IK solutions (each (n,) [rad]) of the world pose ``target`` (4, 4).

    Guesses: ``reference`` first, then the closed-form solutions of a UR arm
    (:class:`~ur_glue_planner.motion.ur_arm_kinematics.UrKinematics`), or for other
    kinematics ``n_random`` uniform ones in [-pi, pi] from a fixed seed. Each is refined by
    Newton (:meth:`Kinematics.ik`), so every solution meets its tolerance on the URDF.
    """
    if isinstance(kin, UrKinematics):
        others = [q for q in kin.ik_solutions(target) if not np.any(np.isnan(q))]
    else:
        others = list(np.random.default_rng(seed).uniform(-math.pi, math.pi, (n_random, kin.n)))
    found: list[np.ndarray] = []
    for guess in [np.asarray(reference, dtype=float)] + others:
        res = kin.ik(target, guess, max_iterations=100)
        if not res.converged:
            continue
        q = _near(res.q, reference, kin.q_min, kin.q_max)
        wrapped = np.mod(q + math.pi, _TWO_PI)
        if all(np.max(np.abs(np.mod(wrapped - np.mod(f + math.pi, _TWO_PI) + math.pi, _TWO_PI) - math.pi)) > 1e-3
               for f in found):
            found.append(q)
    return found


def _grid(path: GluePath, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Arc lengths (n,) [m] at most ``spacing`` apart over the whole path, and the poses (n, 4, 4) there."""
    n = max(2, math.ceil(path.length / spacing) + 1)
    s = np.linspace(0.0, path.length, n)
    targets = np.zeros((n, 4, 4))
    targets[:, :3, :3], targets[:, :3, 3], targets[:, 3, 3] = path.orientation(s), path.position(s), 1.0
    return s, targets


def _touch_reason(clearance: Clearance | None, q: np.ndarray, s: np.ndarray) -> str:
    """Why the arm cannot lay the bead in configurations q (n, n_joints) at arc lengths s (n,), or ''."""
    touch = clearance.first_touch(q) if clearance is not None else None
    return '' if touch is None else f"{touch.describe()} at s = {s[touch.index]:.3f} m"


def _follow_closed_form(kin: UrKinematics, s: np.ndarray, branches: np.ndarray, q_start: np.ndarray,
                        speed: float, max_jump: float,
                        clearance: Clearance | None = None) -> tuple[bool, float, str] | None:
    """:func:`follow` on the grid's closed-form branches made continuous (n, 8, n_joints)
    (:func:`~ur_sim_driver.description.analytic_ik.follow_branch`); None if q_start is on none of them."""
    branch, distance = nearest_branch(branches[0], q_start)
    if distance > 1e-3:
        return None
    q = follow_branch(branches[:, branch], q_start)
    ok = np.all((q >= kin.q_min) & (q <= kin.q_max), axis=1)  # NaN (out of reach) is not ok either
    step = np.abs(np.diff(q, axis=0))
    jumps = np.any(step > max_jump, axis=1)
    fails = np.flatnonzero(~ok)
    k_fail = int(fails[0]) if fails.size else len(s)
    k_jump = int(np.argmax(jumps)) + 1 if np.any(jumps) else len(s)
    if k_fail < len(s) and k_fail <= k_jump:
        where = "out of reach" if np.any(np.isnan(q[k_fail])) else "beyond a joint limit"
        return False, math.inf, f"IK fails at s = {s[k_fail]:.3f} m ({where} in this arm configuration)"
    if k_jump < len(s):
        j = int(np.argmax(step[k_jump - 1]))
        return False, math.inf, f"{kin.joint_names[j]} jumps {step[k_jump - 1, j]:.2f} rad at s = {s[k_jump]:.3f} m"
    touch = _touch_reason(clearance, q, s)
    if touch:
        return False, math.inf, touch
    peak = float(np.max(step / np.diff(s)[:, None] * speed / kin.v_max))
    return True, peak, ""


def follow(path: GluePath, kin: Kinematics, q_start: np.ndarray, speed: float, spacing: float = _SPACING,
           max_jump: float = _MAX_JUMP, clearance: Clearance | None = None) -> tuple[bool, float, str]:
    """Follow the bead from ``q_start`` on a grid of ``spacing`` [m].

    A UR arm follows its closed-form branch through q_start; other kinematics run warm-started
    IK from grid point to grid point. With ``clearance``, a grid point where the arm touches
    itself or the floor makes the branch infeasible.

    Returns:
        (feasible, peak joint-speed usage at ``speed`` [m/s], reason if not feasible). A joint
        step over ``max_jump`` [rad] between grid points is a branch change.
    """
    s, targets = _grid(path, spacing)
    if isinstance(kin, UrKinematics):
        solutions = kin.analytic.solve(targets)
        out = _follow_closed_form(kin, s, follow_branch(solutions, solutions[0]), np.asarray(q_start, dtype=float),
                                  speed, max_jump, clearance)
        if out is not None:
            return out
    q_prev, peak, qs = np.asarray(q_start, dtype=float), 0.0, []
    for k in range(len(s)):
        res = kin.ik(targets[k], q_prev, max_iterations=50)
        if not res.converged:
            return False, math.inf, f"IK fails at s = {s[k]:.3f} m (residual {res.residual_pos:.2e} m)"
        step = np.abs(res.q - q_prev)
        if k > 0 and step.max() > max_jump:
            j = int(np.argmax(step))
            return False, math.inf, f"{kin.joint_names[j]} jumps {step[j]:.2f} rad at s = {s[k]:.3f} m"
        if k > 0:
            peak = max(peak, float(np.max(step / (s[k] - s[k - 1]) * speed / kin.v_max)))
        q_prev = res.q
        qs.append(res.q)
    touch = _touch_reason(clearance, np.array(qs), s)
    return (False, math.inf, touch) if touch else (True, peak, "")


def choose_branch(path: GluePath, kin: Kinematics, reference: np.ndarray, speed: float, *,
                  n_random: int = 24, tie: float = 0.05,
                  clearance: Clearance | None = None) -> tuple[Branch, tuple[Branch, ...]]:
    """The branch to lay the bead in, and every branch examined (chosen one included).

    Args:
        path: The bead.
        kin: Tip kinematics.
        reference: Joint positions (n,) [rad] to prefer, e.g. the home pose.
        speed: Bead speed [m/s], to express the joint-speed demand as a fraction of v_max.
        n_random: Extra pseudo-random IK guesses (fixed seed: the choice is repeatable).
        tie: Peak usages within this fraction count as equal; the nearer branch wins.
        clearance: The arm's collision shapes: a branch in which it touches itself or the floor is infeasible.

    Raises:
        PlanningError: No branch reaches the bead start, or none follows the whole bead.
    """
    reference = np.asarray(reference, dtype=float)
    s, targets = _grid(path, _SPACING)
    start = targets[0]
    qs = start_branches(kin, start, reference, n_random)
    if not qs:
        raise PlanningError(f"no IK solution for the bead start {np.round(start[:3, 3], 4).tolist()} m "
                            f"(frame {kin.frame}): out of reach")
    follows = {}
    if isinstance(kin, UrKinematics):  # all branches from one closed-form solve of the grid
        solutions = kin.analytic.solve(targets)
        branches = follow_branch(solutions, solutions[0])  # all eight, unwrapped once
        follows = {i: _follow_closed_form(kin, s, branches, q, speed, _MAX_JUMP, clearance) for i, q in enumerate(qs)}
    branches = []
    for i, q in enumerate(qs):
        ok, peak, why = follows.get(i) or follow(path, kin, q, speed, _SPACING, _MAX_JUMP, clearance)
        branches.append(Branch(q, ok, peak, float(np.linalg.norm(q - reference)), why))
    good = [b for b in branches if b.feasible]
    if not good:
        reasons = "; ".join(f"branch {np.round(b.q, 2).tolist()}: {b.reason}" for b in branches)
        raise PlanningError(f"no IK branch follows the whole bead ({reasons})")
    best_usage = min(b.peak_usage for b in good)
    near_best = [b for b in good if b.peak_usage <= best_usage * (1.0 + tie)]
    return min(near_best, key=lambda b: b.distance), tuple(branches)
