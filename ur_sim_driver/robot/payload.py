"""A payload on the flange as the robot's set_payload takes it, validated and put in MuJoCo's form.

The UR controller takes the payload's mass, its centre of gravity in the tool flange frame (tool0) and its
inertia about the centre of gravity. MuJoCo keeps a body's inertia as principal moments (``body_inertia``)
along principal axes (``body_iquat``), so a full tensor is diagonalised here, once per set_payload.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur_common.quaternions import quat_from_matrix
from ur_sim_driver.errors import ConfigError

MAX_MASS = 100.0  # [kg] far above any UR's rated payload (UR30: 30 kg): a typo, not a payload
MAX_COG = 5.0  # [m] distance of the centre of gravity from the flange
# Relative slack of the checks that the tensor is positive semi-definite and physically possible.
_INERTIA_RTOL = 1e-9


@dataclass(frozen=True, eq=False)
class Payload:
    """A validated payload.

    Attributes:
        mass: [kg], >= 0 (0: no payload).
        cog: (3,) centre of gravity in tool0 [m].
        inertia: (6,) ixx, iyy, izz, ixy, ixz, iyz about the centre of gravity, tool0 axes [kg m^2].
    """

    mass: float
    cog: np.ndarray
    inertia: np.ndarray

    def tensor(self) -> np.ndarray:
        """The inertia tensor (3, 3) about the centre of gravity in tool0 axes [kg m^2]."""
        xx, yy, zz, xy, xz, yz = self.inertia
        return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])

    def principal(self) -> tuple[np.ndarray, np.ndarray]:
        """Principal moments (3,) [kg m^2] and the principal axes' orientation in tool0 as a MuJoCo
        quaternion (w, x, y, z): ``tensor() == R diag(moments) R^T`` with R the quaternion's matrix."""
        moments, axes = np.linalg.eigh(self.tensor())
        if np.linalg.det(axes) < 0.0:  # eigh may return a reflection; a body frame must be a rotation
            axes[:, 2] = -axes[:, 2]
        return np.maximum(moments, 0.0), quat_from_matrix(axes)


NO_PAYLOAD = Payload(0.0, np.zeros(3), np.zeros(6))


def make_payload(mass: float, cog, inertia=(0.0,) * 6) -> Payload:
    """Validate a payload as the robot's set_payload receives it.

    Args:
        mass: [kg] in [0, MAX_MASS].
        cog: (3,) centre of gravity in tool0 [m], each within MAX_COG of the flange.
        inertia: (6,) ixx, iyy, izz, ixy, ixz, iyz [kg m^2] about the centre of gravity; all zero for a
            point mass. Must be a possible rigid body's: positive semi-definite, and each principal
            moment at most the sum of the other two.

    Raises:
        ConfigError: naming the field, the value and the limit.
    """
    m = float(mass)
    if not (math.isfinite(m) and 0.0 <= m <= MAX_MASS):
        raise ConfigError(f'payload mass = {mass!r} kg is outside [0, {MAX_MASS}] kg')
    c = np.asarray(cog, dtype=float)
    if c.shape != (3,) or not np.all(np.isfinite(c)):
        raise ConfigError(f'payload centre of gravity = {cog!r} must be 3 finite numbers [m]')
    if np.any(np.abs(c) > MAX_COG):
        raise ConfigError(f'payload centre of gravity = {c.tolist()} m is more than {MAX_COG} m from the flange')
    i6 = np.asarray(inertia, dtype=float)
    if i6.shape != (6,) or not np.all(np.isfinite(i6)):
        raise ConfigError(f'payload inertia = {inertia!r} must be 6 finite numbers (ixx, iyy, izz, ixy, ixz, iyz) '
                          '[kg m^2]')
    payload = Payload(m, c, i6)
    moments = np.linalg.eigvalsh(payload.tensor())
    slack = _INERTIA_RTOL * max(1.0, float(np.max(np.abs(moments))))
    if moments[0] < -slack:
        raise ConfigError(f'payload inertia = {i6.tolist()} kg m^2 is not positive semi-definite '
                          f'(principal moments {moments.tolist()})')
    if moments[2] > moments[0] + moments[1] + slack:
        raise ConfigError(f'payload inertia = {i6.tolist()} kg m^2 is not a rigid body\'s: the largest principal '
                          f'moment {moments[2]} exceeds the sum of the other two {moments[0] + moments[1]}')
    return payload
