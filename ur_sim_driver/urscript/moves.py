"""The motions a URScript program commands, as profiles built once and sampled in time (``sample(t)``: joint
positions [rad], velocities [rad/s] and accelerations [rad/s^2] at time t [s] since the move began).

``movej``: every joint along a straight line in joint space, on the trapezoidal speed profile of the joint with the
farthest way (acceleration `a` [rad/s^2], speed `v` [rad/s]); the others scaled to arrive with it. ``movel``: the
tool along a straight line in the base frame, its orientation turning about one axis, on a trapezoidal profile of
the way (`a` [m/s^2], `v` [m/s]; of the angle in [rad] for a pure rotation); the joints by the closed-form IK,
on the branch the move starts in. ``speedj``: from the velocity at the start to `qd` with acceleration `a`, then
constant; ``stopj`` is speedj to rest; ``speedl`` and ``stopl`` the same for the tool's twist (joints by the
Jacobian). ``servoj``: to `q` in time `t`, linearly. A move given a time `t` takes that time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ur_sim_driver.description.analytic_ik import UrAnalyticIK, nearest_branch
from ur_sim_driver.errors import ScriptError

_TINY = 1e-9


@dataclass(frozen=True)
class Trapezoid:
    """A rest-to-rest trapezoidal profile of a way `distance` (>= 0): accelerate, cruise, decelerate."""

    distance: float
    t_accel: float  # [s] each of the two ramps
    duration: float  # [s]
    accel: float

    @staticmethod
    def build(distance: float, a: float, v: float, t: float = 0.0) -> Trapezoid:
        if distance <= _TINY:
            return Trapezoid(0.0, 0.0, max(t, 0.0), a)
        if t > 0.0:  # the given time: the speed that fits it, accelerating with a (faster where a cannot fit)
            disc = a * a * t * t - 4.0 * a * distance
            if disc < 0.0:
                a = 4.0 * distance / (t * t)
                return Trapezoid(distance, t / 2.0, t, a)
            v = (a * t - math.sqrt(disc)) / 2.0
            return Trapezoid(distance, v / a, t, a)
        if distance < v * v / a:  # no cruise: a triangle
            t_a = math.sqrt(distance / a)
            return Trapezoid(distance, t_a, 2.0 * t_a, a)
        return Trapezoid(distance, v / a, distance / v + v / a, a)

    def sample(self, t: float) -> tuple[float, float, float]:
        """(way, speed, acceleration) at time t, clamped to [0, duration]."""
        if self.distance == 0.0 or t <= 0.0:
            return 0.0, 0.0, 0.0
        if t >= self.duration:
            return self.distance, 0.0, 0.0
        a, ta, T = self.accel, self.t_accel, self.duration
        v_top = a * ta
        if t < ta:
            return 0.5 * a * t * t, a * t, a
        if t <= T - ta:
            return 0.5 * a * ta * ta + v_top * (t - ta), v_top, 0.0
        rest = T - t
        return self.distance - 0.5 * a * rest * rest, a * rest, -a


class Move:
    """A motion: `duration` [s] (inf: until another motion replaces it), `returns_after` [s] (when the
    statement that commanded it returns), sample(t)."""

    duration: float
    returns_after: float

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError


class JointLine(Move):
    """movej (and servoj): a straight line in joint space from q0 to q1."""

    def __init__(self, q0: np.ndarray, q1: np.ndarray, a: float, v: float, t: float = 0.0) -> None:
        self.q0, self.q1 = np.array(q0, float), np.array(q1, float)
        self.delta = self.q1 - self.q0
        lead = float(np.abs(self.delta).max())
        self.profile = Trapezoid.build(lead, a, v, t)
        self.duration = self.returns_after = self.profile.duration
        self._scale = self.delta / lead if lead > _TINY else np.zeros_like(self.delta)

    def sample(self, t):
        s, sd, sdd = self.profile.sample(t)
        if t >= self.duration:
            return self.q1.copy(), np.zeros_like(self.q1), np.zeros_like(self.q1)
        return self.q0 + s * self._scale, sd * self._scale, sdd * self._scale


class Servo(Move):
    """servoj: to q1 in time t at constant speed (a stream of servoj calls makes a piecewise linear path)."""

    def __init__(self, q0: np.ndarray, q1: np.ndarray, t: float) -> None:
        self.q0, self.q1 = np.array(q0, float), np.array(q1, float)
        self.duration = self.returns_after = t
        self._speed = (self.q1 - self.q0) / t

    def sample(self, t):
        if t >= self.duration:  # arrived: the next servoj of a stream starts here
            return self.q1.copy(), np.zeros_like(self.q1), np.zeros_like(self.q1)
        return self.q0 + self._speed * max(t, 0.0), self._speed.copy(), np.zeros_like(self.q1)


class Speed(Move):
    """speedj / stopj: from qd0 to qd1 with acceleration a (the joint with the largest change leads), then constant."""

    def __init__(self, q0: np.ndarray, qd0: np.ndarray, qd1: np.ndarray, a: float, t: float | None) -> None:
        self.q0, self.qd0, self.qd1 = np.array(q0, float), np.array(qd0, float), np.array(qd1, float)
        change = self.qd1 - self.qd0
        lead = float(np.abs(change).max())
        self.ramp = lead / a if lead > _TINY else 0.0  # [s]
        self._accel = change / self.ramp if self.ramp > 0.0 else np.zeros_like(change)
        self.duration = self.ramp if not np.any(self.qd1) else math.inf
        self.returns_after = self.ramp if t is None or t <= 0.0 else t

    def sample(self, t):
        t = max(t, 0.0)
        if t < self.ramp:
            return self.q0 + self.qd0 * t + 0.5 * self._accel * t * t, self.qd0 + self._accel * t, self._accel.copy()
        r = self.ramp
        q_ramp = self.q0 + self.qd0 * r + 0.5 * self._accel * r * r
        return q_ramp + self.qd1 * (t - r), self.qd1.copy(), np.zeros_like(self.qd1)


@dataclass(frozen=True)
class Arc:
    """A circle's arc in the base frame: centre (3,) [m], radius [m], unit vectors `u` (to the start) and `w`
    (in the plane, a quarter turn on), and the angle swept [rad] from the start to the end."""

    centre: np.ndarray
    radius: float
    u: np.ndarray
    w: np.ndarray
    angle: float

    @staticmethod
    def through(p0: np.ndarray, via: np.ndarray, p1: np.ndarray) -> Arc:
        """The arc from p0 through `via` to p1; ScriptError when the three points lie on a line."""
        a, b = via - p0, p1 - p0
        normal = np.cross(a, b)
        area = float(np.linalg.norm(normal))
        if area < 1e-9:
            raise ScriptError('movec: the start, the via point and the end lie on a line (no circle through them)')
        normal /= area
        # the circumcentre of the triangle (p0, via, p1)
        centre = p0 + (np.dot(a, a) * np.cross(b, normal) - np.dot(b, b) * np.cross(a, normal)) / (2.0 * area)
        radius = float(np.linalg.norm(p0 - centre))
        u = (p0 - centre) / radius
        w = np.cross(normal, u)

        def angle_of(p):
            r = p - centre
            return math.atan2(float(np.dot(r, w)), float(np.dot(r, u))) % (2.0 * math.pi)
        return Arc(centre, radius, u, w, angle_of(p1))  # via lies between: the sweep from u turns towards w

    def position(self, s: np.ndarray) -> np.ndarray:
        """(n, 3) points at the fractions `s` (n,) of the arc."""
        phi = s[:, None] * self.angle
        return self.centre + self.radius * (np.cos(phi) * self.u + np.sin(phi) * self.w)


class ToolLine(Move):
    """movel (movep, servoc): the tool from pose T0 to T1 (4, 4) in the base frame, joints by IK from q0's branch,
    sampled on the control period's grid at build time (and checked: every sample reachable and within the joint
    limits). With an `arc` (movec) the tool goes along it; its orientation turns from T0's to T1's, or, with
    `fixed` (movec's mode 1), turns with the arc's tangent."""

    def __init__(self, ik: UrAnalyticIK, q0: np.ndarray, t0: np.ndarray, t1: np.ndarray, a: float, v: float,
                 t: float, dt: float, q_min: np.ndarray, q_max: np.ndarray, arc: Arc | None = None,
                 fixed: bool = False, name: str = 'movel') -> None:
        way = float(np.linalg.norm(t1[:3, 3] - t0[:3, 3])) if arc is None else arc.radius * arc.angle
        rotations = Rotation.from_matrix(np.stack([t0[:3, :3], t1[:3, :3]]))
        angle = float((rotations[0].inv() * rotations[1]).magnitude())
        self.profile = Trapezoid.build(way if way > 1e-6 else angle, a, v, t)
        self.duration = self.returns_after = self.profile.duration
        n = max(2, int(math.ceil(self.duration / dt)) + 1)
        self.times = np.linspace(0.0, self.duration, n)
        length = self.profile.distance
        s = np.array([self.profile.sample(ti)[0] / length if length > 0 else 1.0 for ti in self.times])
        poses = np.tile(np.eye(4), (n, 1, 1))
        if arc is None:
            poses[:, :3, 3] = t0[:3, 3] + s[:, None] * (t1[:3, 3] - t0[:3, 3])
        else:
            poses[:, :3, 3] = arc.position(s)
        if fixed and arc is not None:  # turning with the tangent: about the circle's normal
            normal = np.cross(arc.u, arc.w)
            poses[:, :3, :3] = (Rotation.from_rotvec(np.outer(s * arc.angle, normal)) * rotations[0]).as_matrix()
        else:
            poses[:, :3, :3] = Slerp([0.0, 1.0], rotations)(s).as_matrix()
        solutions = ik.solve(poses)  # (n, 8, 6), NaN where unreachable
        q = np.empty((n, len(q0)))
        previous = np.asarray(q0, float)
        for k in range(n):
            branch, _ = nearest_branch(solutions[k], previous)
            candidate = solutions[k, branch]
            if not np.all(np.isfinite(candidate)):
                raise ScriptError(f'{name}: the pose at {100 * s[k]:.0f} % of the way is out of reach')
            previous = previous + _wrap(candidate - previous)  # the nearest turn of each joint
            q[k] = previous
        outside = np.flatnonzero(np.any((q < q_min) | (q > q_max), axis=0))
        if outside.size:
            j = int(outside[0])
            raise ScriptError(f'{name}: joint {j} would leave its limits [{q_min[j]:.4f}, {q_max[j]:.4f}] rad '
                              f'on the way (reaching {q[:, j].min():.4f} .. {q[:, j].max():.4f})')
        self.q = q
        self.qd = np.gradient(q, self.times, axis=0) if n > 2 else np.zeros_like(q)

    def sample(self, t):
        if t >= self.duration:
            return self.q[-1].copy(), np.zeros(self.q.shape[1]), np.zeros(self.q.shape[1])
        t = max(t, 0.0)
        q = np.array([np.interp(t, self.times, self.q[:, j]) for j in range(self.q.shape[1])])
        qd = np.array([np.interp(t, self.times, self.qd[:, j]) for j in range(self.q.shape[1])])
        return q, qd, np.zeros_like(q)


class ToolSpeed(Move):
    """speedl / stopl: the tool's twist (linear [m/s], angular [rad/s], base axes) from xd0 to xd1 with acceleration
    a [m/s^2] (a_rot [rad/s^2] for the turn), then constant; the joints follow by the damped inverse of the arm's
    Jacobian, integrated in steps of at most `dt`. Stateful: sample times must not decrease."""

    def __init__(self, ik: UrAnalyticIK, q0: np.ndarray, xd0: np.ndarray, xd1: np.ndarray, a: float,
                 a_rot: float, t: float | None, dt: float) -> None:
        self.ik, self.dt = ik, dt
        self.xd0, self.xd1 = np.array(xd0, float), np.array(xd1, float)
        change = self.xd1 - self.xd0
        self.ramp = max(float(np.linalg.norm(change[:3])) / a, float(np.linalg.norm(change[3:])) / a_rot)
        self.duration = self.ramp if not np.any(self.xd1) else math.inf
        self.returns_after = self.ramp if t is None or t <= 0.0 else t
        self._t, self._q = 0.0, np.array(q0, float)
        self._qd = self._joint_speed(self._q, self.xd0)

    def twist(self, t: float) -> np.ndarray:
        if t >= self.ramp:
            return self.xd1.copy()
        return self.xd0 + (self.xd1 - self.xd0) * (t / self.ramp)

    def sample(self, t):
        qd_before = self._qd
        while self._t < t - 1e-12:
            h = min(self.dt, t - self._t)
            self._qd = self._joint_speed(self._q, self.twist(self._t + h / 2))
            self._q = self._q + self._qd * h
            self._t += h
        qdd = (self._qd - qd_before) / self.dt if t > 0 else np.zeros_like(self._q)
        return self._q.copy(), self._qd.copy(), qdd

    def _joint_speed(self, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
        if not np.any(twist):
            return np.zeros_like(q)
        j = tool_jacobian(self.ik, q)
        damping = 1e-4  # keeps the speeds finite near a singularity (the robot's servo limits them anyway)
        return j.T @ np.linalg.solve(j @ j.T + damping * np.eye(6), twist)


def tool_jacobian(ik: UrAnalyticIK, q: np.ndarray, step: float = 1e-7) -> np.ndarray:
    """(6, 6) the tool's twist (linear, angular; base axes) per joint speed, by central differences of the FK."""
    q = np.asarray(q, float)
    shifts = np.concatenate([q + step * np.eye(len(q)), q - step * np.eye(len(q))])
    poses = ik.fk(shifts)
    n = len(q)
    j = np.empty((6, n))
    for k in range(n):
        plus, minus = poses[k], poses[n + k]
        j[:3, k] = (plus[:3, 3] - minus[:3, 3]) / (2 * step)
        j[3:, k] = Rotation.from_matrix(plus[:3, :3] @ minus[:3, :3].T).as_rotvec() / (2 * step)
    return j


def _wrap(d: np.ndarray) -> np.ndarray:
    return (d + math.pi) % (2.0 * math.pi) - math.pi
