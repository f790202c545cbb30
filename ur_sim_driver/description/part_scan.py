"""The cell's part scanners: laser profile scanners fixed over the fixture, and the cloud they publish.

Shared by the simulator (which casts their beams onto the scene) and ur_glue_planner (which reads their cloud).

* :class:`ProfileScanner` (frozen): one laser line (a fan of ``points`` beams over ``fov_deg`` in the plane of
  ``direction`` and ``line``, from ``origin``), in the MuJoCo world [m]. :meth:`ProfileScanner.beams` gives the
  unit beam directions, first to last along ``line``.
* :class:`ScannerSetup` (frozen): the scanners of a scene (the ``scanners:`` block of a scene file), which bodies
  they see (``targets``), their range [m], noise [m, 1 sigma along the beam] and rate [Hz of simulated time].
  :func:`parse_scanners` reads the block; every error names the field, the value and the limit.
* :func:`to_cloud` / :func:`from_cloud`: sensor_msgs/PointCloud2, organised: one row per scanner, one column per
  beam, fields ``x, y, z`` (float32 [m]), NaN where a beam saw nothing within range (``is_dense`` false), as a
  ROS driver of a profile scanner publishes it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ur_sim_driver.errors import ConfigError

if TYPE_CHECKING:
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import PointCloud2

CLOUD_DTYPE = np.dtype([('x', '<f4'), ('y', '<f4'), ('z', '<f4')])
_FLOAT32 = 7  # sensor_msgs/PointField.FLOAT32
MAX_POINTS = 4096  # beams of one scanner (a profile scanner has 640 to 4096)


@dataclass(frozen=True)
class ProfileScanner:
    """One laser profile scanner: ``origin`` (3,) [m], unit ``direction`` (3,) of its middle beam, unit ``line``
    (3,) across which the fan opens (perpendicular to ``direction``), ``fov_deg`` [deg], ``points`` beams."""

    name: str
    origin: tuple[float, float, float]
    direction: tuple[float, float, float]
    line: tuple[float, float, float]
    fov_deg: float
    points: int

    def beams(self) -> np.ndarray:
        """Unit beam directions (points, 3), equally spaced in angle, from -fov/2 (against ``line``) to +fov/2."""
        half = math.radians(self.fov_deg) / 2.0
        angles = np.linspace(-half, half, self.points)
        d, u = np.asarray(self.direction), np.asarray(self.line)
        return np.cos(angles)[:, None] * d + np.sin(angles)[:, None] * u


@dataclass(frozen=True)
class ScannerSetup:
    """The scanners of a scene: what they see, how far, how noisy, how often, and each unit."""

    targets: tuple[str, ...]
    max_range: float
    noise: float
    rate: float
    units: tuple[ProfileScanner, ...]


def _vector(value: Any, where: str, unit: bool) -> tuple[float, float, float]:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = np.empty(0)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ConfigError(f'{where} = {value!r} must be three finite numbers [x, y, z]')
    if unit:
        n = float(np.linalg.norm(v))
        if abs(n - 1.0) > 1e-3:
            raise ConfigError(f'{where} = {value!r} must be a unit vector (its length is {n:.4f})')
        v = v / n
    return tuple(float(x) for x in v)


def _number(value: Any, where: str, lo: float, hi: float) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f'{where} = {value!r} is not a number') from None
    if not (math.isfinite(x) and lo < x <= hi):
        raise ConfigError(f'{where} = {value!r} is outside ({lo}, {hi}]')
    return x


def parse_scanners(block: Any, where: str = 'scanners') -> ScannerSetup:
    """The ``scanners`` block of a scene file as a ScannerSetup.

    Raises:
        ConfigError: a missing or unknown key, or a value out of its range (named, with the limit).
    """
    keys = {'targets', 'max_range', 'noise', 'rate', 'units'}
    if not isinstance(block, dict) or set(block) - keys or not {'targets', 'units'} <= set(block):
        raise ConfigError(f"{where} must be a mapping with 'targets' and 'units' (optional: max_range, noise, rate); "
                          f'got {sorted(block) if isinstance(block, dict) else block!r}')
    targets = block['targets']
    if not isinstance(targets, list) or not targets or not all(isinstance(t, str) for t in targets):
        raise ConfigError(f'{where}.targets = {targets!r} must be a list of body names')
    if not isinstance(block['units'], list) or not block['units']:
        raise ConfigError(f"{where}.units must be a non-empty list of scanners")
    units, names = [], set()
    unit_keys = {'name', 'origin', 'direction', 'line', 'fov_deg', 'points'}
    for i, u in enumerate(block['units']):
        at = f'{where}.units[{i}]'
        if not isinstance(u, dict) or set(u) != unit_keys:
            raise ConfigError(f'{at} must have exactly the keys {", ".join(sorted(unit_keys))}; got '
                              f'{sorted(u) if isinstance(u, dict) else u!r}')
        name = str(u['name'])
        if name in names:
            raise ConfigError(f'{at}.name {name!r} is used twice')
        names.add(name)
        d, line = _vector(u['direction'], f'{at}.direction', True), _vector(u['line'], f'{at}.line', True)
        if abs(float(np.dot(d, line))) > 1e-3:
            raise ConfigError(f'{at}.line must be perpendicular to direction (their dot product is '
                              f'{float(np.dot(d, line)):.4f})')
        points = u['points']
        if not isinstance(points, int) or isinstance(points, bool) or not 2 <= points <= MAX_POINTS:
            raise ConfigError(f'{at}.points = {points!r} must be an integer in [2, {MAX_POINTS}]')
        units.append(ProfileScanner(name, _vector(u['origin'], f'{at}.origin', False), d, line,
                                    _number(u['fov_deg'], f'{at}.fov_deg', 0.0, 120.0), points))
    return ScannerSetup(targets=tuple(targets),
                        max_range=_number(block.get('max_range', 0.5), f'{where}.max_range', 0.0, 5.0),
                        noise=_number(block.get('noise', 1e-4), f'{where}.noise', -1e-12, 0.01),
                        rate=_number(block.get('rate', 5.0), f'{where}.rate', 0.0, 100.0),
                        units=tuple(units))


def to_cloud(points: np.ndarray, frame_id: str, stamp: Time) -> PointCloud2:
    """Profiles (rows, beams, 3) [m], NaN where nothing was seen, as an organised PointCloud2 (x, y, z float32)."""
    from sensor_msgs.msg import PointCloud2, PointField

    rows, cols = points.shape[:2]
    data = np.empty((rows, cols), dtype=CLOUD_DTYPE)
    for axis, name in enumerate('xyz'):
        data[name] = points[..., axis]
    msg = PointCloud2()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    msg.height, msg.width = rows, cols
    msg.fields = [PointField(name=n, offset=4 * k, datatype=_FLOAT32, count=1) for k, n in enumerate('xyz')]
    msg.is_bigendian = False
    msg.point_step = CLOUD_DTYPE.itemsize
    msg.row_step = CLOUD_DTYPE.itemsize * cols
    msg.is_dense = bool(np.all(np.isfinite(points)))
    msg.data = data.tobytes()
    return msg


def from_cloud(msg: PointCloud2) -> np.ndarray:
    """The profiles (height, width, 3) [m] of an organised cloud with float32 x, y, z (NaN kept).

    Raises:
        ValueError: a field is missing or not float32, or the data is shorter than the header says.
    """
    fields = {f.name: f for f in msg.fields}
    for name in 'xyz':
        f = fields.get(name)
        if f is None or f.datatype != _FLOAT32:
            raise ValueError(f"PointCloud2 needs a float32 field '{name}' (fields: {', '.join(fields) or 'none'})")
    dtype = np.dtype({'names': list('xyz'), 'formats': ['>f4' if msg.is_bigendian else '<f4'] * 3,
                      'offsets': [fields[n].offset for n in 'xyz'], 'itemsize': msg.point_step})
    n = msg.width * msg.height
    data = bytes(msg.data)
    if len(data) < n * msg.point_step:
        raise ValueError(f'PointCloud2 data has {len(data)} bytes; {n} points x {msg.point_step} need '
                         f'{n * msg.point_step}')
    rows = np.frombuffer(data, dtype=dtype, count=n)
    return np.stack([rows['x'], rows['y'], rows['z']], axis=-1).astype(float).reshape(msg.height, msg.width, 3)
