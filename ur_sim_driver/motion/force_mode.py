"""The robot's force mode (URScript ``force_mode``), as a pure function of the cycle: no ROS, no MuJoCo.

Along and about the *compliant* axes of the force frame, the robot moves its TCP to apply the requested wrench to
its environment: the difference between the requested wrench and the one it applies drives the TCP's velocity on
that axis, like a virtual mass, slowed by the damping, and capped by the axis's speed limit. With nothing to push
against the TCP keeps accelerating along the wrench up to that limit; against a surface it moves until it pushes
with the requested force. The other axes follow the program (the active controller's reference). ``damping`` in
[0, 1] (1: the TCP stops at once when no force drives it, 0: it keeps its speed) and ``gain_scaling`` in [0, 2]
(scales the drive) are the robot's ``force_mode_set_damping`` and ``force_mode_set_gain_scaling``.

UR does not publish its force controller. The virtual mass and the damping rate are ours: with the driver's defaults
(damping 0.025, gain scaling 0.5) a 10 N request in free space reaches 3 cm in about 1.1 s, and pressing on the
floor settles at the requested force (``test_force_mode.py``).

Force frame, by ``kind`` (URScript's ``type``): 2 the task frame as given; 1 its y axis turned to point from the
TCP towards the task frame's origin; 3 its x axis turned to the TCP velocity's projection onto the task frame's
x-y plane (as given while the TCP does not move in that plane).

Deviation limits: on the non-compliant axes the limits are the largest deviation of the TCP from where the program
holds it, along (translation) or about (rotation) each axis of the force frame, before the robot stops (URScript's
``force_mode`` ``limits``; the CB3 manual's Force command: "the maximum deviation from the program trajectory which
is allowed before the robot protective stops"). :func:`deviation` measures it, :func:`deviation_cause` compares it
with the limits.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = ('x', 'y', 'z', 'rx', 'ry', 'rz')
VIRTUAL_MASS = 50.0  # [kg] per compliant translation: the drive of a force error [N] as an acceleration
VIRTUAL_INERTIA = 1.0  # [kg m^2] per compliant rotation
DAMPING_RATE = 100.0  # [1/s] the velocity's decay rate at damping 1
TCP_TO_ORIGIN, NO_TRANSFORM, TCP_VELOCITY_TO_X_Y = 1, 2, 3


@dataclass(frozen=True, eq=False)
class ForceModeSpec:
    """A force mode request, in the robot's base frame.

    Attributes:
        task_frame: (4, 4) the task frame's pose in base.
        selection: (6,) bool, compliant axes (x, y, z, rx, ry, rz of the force frame).
        wrench: (6,) force [N] and torque [N m] to apply to the environment, force frame axes.
        kind: 1, 2 or 3 (see the module).
        limits: (6,) speed limits of compliant axes [m/s, rad/s]; deviation limits of the others [m, rad].
        damping: [0, 1].
        gain_scaling: [0, 2].
    """

    task_frame: np.ndarray
    selection: np.ndarray
    wrench: np.ndarray
    kind: int
    limits: np.ndarray
    damping: float
    gain_scaling: float


def force_frame(spec: ForceModeSpec, tcp_position: np.ndarray, tcp_velocity: np.ndarray) -> np.ndarray:
    """(3, 3) the force frame's axes in base, for the TCP at `tcp_position` (3,) [m] moving at `tcp_velocity` (3,)
    [m/s]."""
    r = spec.task_frame[:3, :3]
    if spec.kind == TCP_TO_ORIGIN:
        y = spec.task_frame[:3, 3] - tcp_position
        z = r[:, 2] - (r[:, 2] @ y) / max(y @ y, 1e-12) * y
        if np.linalg.norm(y) < 1e-6 or np.linalg.norm(z) < 1e-6:
            return r
        y, z = y / np.linalg.norm(y), z / np.linalg.norm(z)
        return np.column_stack((np.cross(y, z), y, z))
    if spec.kind == TCP_VELOCITY_TO_X_Y:
        z = r[:, 2]
        x = tcp_velocity - (tcp_velocity @ z) * z
        if np.linalg.norm(x) < 1e-6:
            return r
        x = x / np.linalg.norm(x)
        return np.column_stack((x, np.cross(z, x), z))
    return r


def admittance_step(spec: ForceModeSpec, velocity: np.ndarray, applied: np.ndarray, dt: float) -> np.ndarray:
    """The compliant axes' velocity (6,) [m/s, rad/s] after `dt` [s], force frame axes.

    Args:
        velocity: (6,) the velocity now (zero on the other axes).
        applied: (6,) the wrench the robot applies to its environment now [N, N m], force frame axes.
    """
    mass = np.array([VIRTUAL_MASS] * 3 + [VIRTUAL_INERTIA] * 3)
    drive = spec.gain_scaling * (spec.wrench - applied) / mass
    decay = np.exp(-spec.damping * DAMPING_RATE * dt)
    v = velocity * decay + drive * (1.0 - decay) / (spec.damping * DAMPING_RATE) if spec.damping > 0.0 \
        else velocity + drive * dt
    v = np.clip(v, -spec.limits, spec.limits)
    return np.where(spec.selection, v, 0.0)


def deviation(axes: np.ndarray, actual: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(6,) the TCP's deviation from where the program holds it, along and about the force frame's axes [m, rad].

    Args:
        axes: (3, 3) the force frame's axes in base (:func:`force_frame`).
        actual: (4, 4) the TCP's pose in base.
        target: (4, 4) the pose the program holds the TCP at, in base.
    The translation is the difference of the positions; the rotation is the rotation vector of the turn from
    `target` to `actual` (base axes), both expressed in the force frame's axes.
    """
    moved = actual[:3, 3] - target[:3, 3]
    turned = rotation_vector(actual[:3, :3] @ target[:3, :3].T)
    return np.concatenate((axes.T @ moved, axes.T @ turned))


def deviation_cause(spec: ForceModeSpec, deviation: np.ndarray) -> str | None:
    """Why `deviation` (6,) [m, rad] (:func:`deviation`) stops the robot: each non-compliant axis deviating further
    than its limit, named with its deviation and limit; None while every one is within (a deviation equal to its
    limit is within). The compliant axes' limits are speeds and are not compared here."""
    over = ~spec.selection & (np.abs(deviation) > spec.limits)
    if not over.any():
        return None
    parts = []
    for i in np.flatnonzero(over):
        if i < 3:  # translations in mm: the limits are usually a few of them
            parts.append(f'{deviation[i] * 1e3:+.2f} mm along {AXES[i]} (limit {spec.limits[i] * 1e3:.2f} mm)')
        else:
            parts.append(f'{deviation[i]:+.4f} rad about {AXES[i][1]} (limit {spec.limits[i]:.4f} rad)')
    return ('force mode: the TCP deviates from where the program holds it beyond the deviation limit of a '
            f'non-compliant axis of the force frame: {"; ".join(parts)}')


def rotation_vector(r: np.ndarray) -> np.ndarray:
    """(3,) the rotation vector (axis times angle [rad], angle in [0, pi]) of the rotation matrix `r` (3, 3).

    Not SciPy's ``Rotation.from_matrix(r).as_rotvec()`` (which the tests compare it with): that took 136 us a call
    against 16 us here, every cycle of force mode in a loop of about 50 us a cycle."""
    skew = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])  # 2 sin(angle) axis
    # From sine and cosine: accurate at small angles too, where the arccosine of the trace loses half the digits.
    angle = float(np.arctan2(np.linalg.norm(skew) / 2.0, (np.trace(r) - 1.0) / 2.0))
    if angle < 1e-6:
        return 0.5 * skew  # first order: the angle's sine is the angle
    if np.pi - angle > 1e-4:
        return angle / (2.0 * np.sin(angle)) * skew
    # Near a half turn the sine vanishes: the axis a from the symmetric part, cos(angle) I + (1 - cos(angle)) a a^T.
    cos = np.cos(angle)
    outer = ((r + r.T) / 2.0 - cos * np.eye(3)) / (1.0 - cos)
    i = int(np.argmax(np.diag(outer)))
    axis = outer[:, i] / np.sqrt(outer[i, i])
    if axis @ skew < 0.0:  # the sign the remaining sine still shows
        axis = -axis
    return angle * axis / np.linalg.norm(axis)
