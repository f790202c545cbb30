"""UR type parameters (kinematics, dynamics, limits) read from ``config/ur_types/<type>.yaml``.

Also holds the frame helpers both model builders share, and the nominal ur_description
joint origins derived from the DH parameters, so that the URDF and the MJCF are built from
the very same numbers.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from ur_common import paths
from ur_sim_driver.errors import ConfigError

# The types the UR driver supports (jazzy a16a268: hardware_interface.cpp robotTypeFromString), one file each.
UR_TYPES: tuple[str, ...] = ('ur3', 'ur3e', 'ur5', 'ur5e', 'ur7e', 'ur8long', 'ur10', 'ur10e', 'ur12e', 'ur15',
                             'ur16e', 'ur18', 'ur20', 'ur30')
SERIES: tuple[str, ...] = ('cb3', 'e', 'ur')  # CB3, e-Series, UR Series
JOINT_NAMES: tuple[str, ...] = (
    'shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
    'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint',
)
# Child link of each joint, in the order of JOINT_NAMES (ur_description names).
LINK_NAMES: tuple[str, ...] = (
    'shoulder_link', 'upper_arm_link', 'forearm_link',
    'wrist_1_link', 'wrist_2_link', 'wrist_3_link',
)
_YAML_LINKS = ('shoulder', 'upper_arm', 'forearm', 'wrist_1', 'wrist_2', 'wrist_3')
_RADIUS_KEYS = ('base', 'shoulder', 'upper_arm', 'elbow', 'forearm', 'wrist')


def joint_names(tf_prefix: str = '') -> tuple[str, ...]:
    """The six UR joint names with ``tf_prefix`` prepended."""
    return tuple(tf_prefix + n for n in JOINT_NAMES)


# --- frame helpers -------------------------------------------------------------------------

def rpy_to_matrix(rpy: Any) -> np.ndarray:
    """Rotation matrix (3, 3) of URDF roll-pitch-yaw angles [rad]: Rz(yaw) Ry(pitch) Rx(roll) (fixed axes x, y, z)."""
    return Rotation.from_euler('xyz', [float(v) for v in rpy]).as_matrix()


def matrix_to_rpy(rot: np.ndarray) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw [rad] of a rotation matrix (3, 3); yaw = 0 at gimbal lock."""
    with warnings.catch_warnings():  # SciPy says so when it sets yaw to 0 at the gimbal lock: that is the contract
        warnings.simplefilter('ignore', UserWarning)
        roll, pitch, yaw = Rotation.from_matrix(np.asarray(rot, dtype=float)).as_euler('xyz')
    return float(roll), float(pitch), float(yaw)


@dataclass(frozen=True)
class Origin:
    """A URDF-style origin: translation ``xyz`` [m] and roll-pitch-yaw ``rpy`` [rad]."""

    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def matrix(self) -> np.ndarray:
        """Homogeneous transform (4, 4)."""
        m = np.eye(4)
        m[:3, :3] = rpy_to_matrix(self.rpy)
        m[:3, 3] = self.xyz
        return m

    @staticmethod
    def from_matrix(m: np.ndarray) -> Origin:
        """Origin of a homogeneous transform (4, 4)."""
        m = np.asarray(m, dtype=float)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise ConfigError(f'pose must be a finite 4x4 matrix, got shape {m.shape}')
        if np.abs(m[:3, :3] @ m[:3, :3].T - np.eye(3)).max() > 1e-6 or np.linalg.det(m[:3, :3]) < 0:
            raise ConfigError('pose rotation part is not a proper rotation matrix')
        return Origin(tuple(float(v) for v in m[:3, 3]), matrix_to_rpy(m[:3, :3]))


# --- parameters ----------------------------------------------------------------------------

@dataclass(frozen=True)
class DH:
    """UR Denavit-Hartenberg lengths [m] (a1 = a4 = a5 = d2 = d3 = 0)."""

    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float


def _frozen(a: Any, shape: tuple[int, ...], what: str, scale: float = 1.0) -> np.ndarray:
    try:
        arr = np.array(a, dtype=float) * scale
    except (TypeError, ValueError):
        arr = np.empty(0)
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise ConfigError(f'{what}: expected {shape} finite numbers, got {a!r}')
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class URParams:
    """All numbers describing one UR type; arrays are read-only and in joint order.

    Attributes:
        name: UR type, e.g. ``'ur5e'``.
        model: the robot type its controller reports, e.g. ``'UR5'`` for a ur5e or a ur7e.
        series: ``'cb3'``, ``'e'`` (e-Series) or ``'ur'`` (UR Series).
        payload: rated payload [kg]; reach: [m] (data sheet).
        software_minimum, software_default: controller software (major, minor, bugfix): the first release
            that runs the type, and the one ur_sim runs unless told otherwise.
        dh: DH lengths [m].
        masses: link masses (6,) [kg].
        coms: centres of mass (6, 3) [m], each in its link frame.
        inertias: (6, 6), rows ixx, ixy, ixz, iyy, iyz, izz [kg m^2] about the com, in axes
            rotated by ``inertia_rpy`` (6, 3) [rad] from the link frame (URDF inertial origin).
        inertia_rpy: see ``inertias``.
        base_mass: [kg], base_radius: [m], base_length: [m]: cylinder inertia of base_link_inertia.
        q_min, q_max: position limits (6,) [rad].
        v_max: velocity limits (6,) [rad/s].
        effort_max: torque limits (6,) [N m].
        a_max: joint acceleration limit [rad/s^2] (not published; MoveIt's conservative value).
        control_rate: controller rate [Hz] (125 CB3, 500 e-Series).
        armature: reflected rotor inertia (6,) [kg m^2] (simulation estimate).
        damping: viscous joint friction (6,) [N m s/rad] (simulation estimate).
        coulomb: Coulomb joint friction (6,) [N m] (simulation estimate; felt only under torque control, where
            the robot's friction compensation leaves part of it, see ``Simulator.advance_torque``).
        torque_constant: (6,) [N m/A] each joint's torque at its output per ampere of motor current, gear included:
            how the reported motor currents follow from the simulated drive torques (``robot/motor_currents.py``).
        shoulder_offset, elbow_offset: lateral offsets of the arm tubes [m] (collision shapes).
        collision_radius: read-only map part -> radius [m] for base, shoulder, upper_arm,
            elbow, forearm, wrist.
    """

    name: str
    model: str
    series: str
    payload: float
    reach: float
    software_minimum: tuple[int, int, int]
    software_default: tuple[int, int, int]
    dh: DH
    masses: np.ndarray
    coms: np.ndarray
    inertias: np.ndarray
    inertia_rpy: np.ndarray
    base_mass: float
    base_radius: float
    base_length: float
    q_min: np.ndarray
    q_max: np.ndarray
    v_max: np.ndarray
    effort_max: np.ndarray
    a_max: float
    control_rate: float
    armature: np.ndarray
    damping: np.ndarray
    coulomb: np.ndarray
    torque_constant: np.ndarray
    shoulder_offset: float
    elbow_offset: float
    collision_radius: Mapping[str, float] = field(default_factory=dict)

    def joint_origins(self) -> tuple[Origin, ...]:
        """Nominal ur_description joint origins (6,), parent link frame to joint frame.

        These are what ``default_kinematics.yaml`` holds for an uncalibrated robot; upstream
        stores pi/2 rounded and tiny z residues, we use the exact DH-derived values.
        """
        d, hp = self.dh, math.pi / 2
        return (
            Origin((0.0, 0.0, d.d1)),
            Origin(rpy=(hp, 0.0, 0.0)),
            Origin((d.a2, 0.0, 0.0)),
            Origin((d.a3, 0.0, d.d4)),
            Origin((0.0, -d.d5, 0.0), (hp, 0.0, 0.0)),
            Origin((0.0, d.d6, 0.0), (hp, math.pi, math.pi)),
        )


def config_dir() -> Path:
    """Directory holding ``<type>.yaml``: the source tree first, then the installed share dir."""
    return paths.config_dir() / 'ur_types'


def _get(d: dict, key: str, where: str) -> Any:
    if not isinstance(d, dict) or key not in d:
        raise ConfigError(f'{where}: missing key {key!r}')
    return d[key]


def _release(text: Any, what: str) -> tuple[int, int, int]:
    parts = str(text).split('.')
    if len(parts) != 3 or not all(p.isdigit() for p in parts):
        raise ConfigError(f'{what}: expected a release major.minor.bugfix, got {text!r}')
    return int(parts[0]), int(parts[1]), int(parts[2])


def load_ur_params(ur_type: str) -> URParams:
    """Read the parameters of ``ur_type`` (one of ``UR_TYPES``, case-insensitive); cached.

    Raises:
        ConfigError: unknown type, missing file or key, or malformed numbers.
    """
    key = ur_type.strip().lower() if isinstance(ur_type, str) else None
    if key not in UR_TYPES:
        raise ConfigError(f'ur_type {ur_type!r} is not supported; choose one of: {", ".join(UR_TYPES)}')
    return _load(key)


@cache
def _load(key: str) -> URParams:
    path = config_dir() / f'{key}.yaml'
    try:
        raw = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f'cannot read UR parameters {path}: {exc}') from exc
    w = str(path)
    links = _get(raw, 'links', w)
    per_link = [_get(links, n, f'{w}: links') for n in _YAML_LINKS]
    lim, sim = _get(raw, 'limits', w), _get(raw, 'simulation', w)
    deg = math.pi / 180.0
    pos = _frozen(_get(lim, 'position_deg', w), (6,), f'{w}: limits.position_deg', deg)
    radii = _get(sim, 'collision_radius', w)
    base, off, dh = _get(raw, 'base', w), _get(raw, 'offsets', w), _get(raw, 'dh', w)
    software = _get(raw, 'software', w)
    series = str(_get(raw, 'series', w))
    if series not in SERIES:
        raise ConfigError(f'{w}: series {series!r} is not one of {", ".join(SERIES)}')
    try:
        params = URParams(
            name=key,
            model=str(_get(raw, 'model', w)),
            series=series,
            payload=float(_get(raw, 'payload', w)),
            reach=float(_get(raw, 'reach', w)),
            software_minimum=_release(_get(software, 'minimum', f'{w}: software'), f'{w}: software.minimum'),
            software_default=_release(_get(software, 'default', f'{w}: software'), f'{w}: software.default'),
            dh=DH(**{k: float(_get(dh, k, f'{w}: dh')) for k in ('d1', 'a2', 'a3', 'd4', 'd5', 'd6')}),
            masses=_frozen([_get(p, 'mass', w) for p in per_link], (6,), f'{w}: mass'),
            coms=_frozen([_get(p, 'com', w) for p in per_link], (6, 3), f'{w}: com'),
            inertias=_frozen([_get(p, 'inertia', w) for p in per_link], (6, 6), f'{w}: inertia'),
            inertia_rpy=_frozen([_get(p, 'inertia_rpy', w) for p in per_link], (6, 3), f'{w}: inertia_rpy'),
            base_mass=float(_get(base, 'mass', w)),
            base_radius=float(_get(base, 'radius', w)),
            base_length=float(_get(base, 'length', w)),
            q_min=_frozen(-pos, (6,), 'q_min'),
            q_max=_frozen(pos, (6,), 'q_max'),
            v_max=_frozen(_get(lim, 'velocity_deg_s', w), (6,), f'{w}: limits.velocity_deg_s', deg),
            effort_max=_frozen(_get(lim, 'effort', w), (6,), f'{w}: limits.effort'),
            a_max=float(_get(lim, 'acceleration', w)),
            control_rate=float(_get(raw, 'control_rate', w)),
            armature=_frozen(_get(sim, 'armature', w), (6,), f'{w}: simulation.armature'),
            damping=_frozen(_get(sim, 'damping', w), (6,), f'{w}: simulation.damping'),
            coulomb=_frozen(_get(sim, 'coulomb', w), (6,), f'{w}: simulation.coulomb'),
            torque_constant=_frozen(_get(_get(raw, 'drives', w), 'torque_constant', f'{w}: drives'), (6,),
                                    f'{w}: drives.torque_constant'),
            shoulder_offset=float(_get(off, 'shoulder', w)),
            elbow_offset=float(_get(off, 'elbow', w)),
            collision_radius=MappingProxyType(
                {k: float(_get(radii, k, f'{w}: collision_radius')) for k in _RADIUS_KEYS}),
        )
    except (TypeError, ValueError) as exc:
        raise ConfigError(f'{w}: malformed number: {exc}') from exc
    positive = {'mass': params.masses, 'limits.position_deg': params.q_max, 'limits.velocity_deg_s': params.v_max,
                'limits.effort': params.effort_max, 'limits.acceleration': params.a_max,
                'drives.torque_constant': params.torque_constant,
                'control_rate': params.control_rate, 'payload': params.payload, 'reach': params.reach,
                'collision_radius': list(params.collision_radius.values())}
    for what, values in positive.items():
        if np.any(np.asarray(values) <= 0.0):
            raise ConfigError(f'{w}: {what} must be > 0, got {values}')
    if params.software_default < params.software_minimum:
        raise ConfigError(f'{w}: software.default {params.software_default} is older than software.minimum '
                          f'{params.software_minimum}')
    return params
