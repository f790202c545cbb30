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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
