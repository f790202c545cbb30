"""A glue bead as laid on a surface: centre line, width, height and time of every point; its section's shape.

Shared by the simulator's dispenser and ur_glue_planner's listener, report and video, so both sides agree on the
bead's shape and its message layout:

* ``ASPECT`` and :func:`section` (area [m^2]) -> (width, height) [m]: the bead's triangular section on its base.

* :class:`Bead` (frozen): ``points`` (N, 3) [m], centre of the bead's base on the surface, in the frame
  the bead is expressed in (ur_sim: ``<tf_prefix>base``); ``widths`` (N,) [m] across the base;
  ``heights`` (N,) [m] above the surface; ``times`` (N,) [s] of simulated time at which the point's
  material reached the surface. Points are in laying order along the centre line; ``Bead.empty()`` has
  N = 0; ``len(bead)``, ``bead.length()`` [m].
* :func:`to_cloud` (Bead, frame_id, stamp) -> sensor_msgs/PointCloud2 with the fields ``x, y, z, width,
  height`` (float32, [m]) and ``t`` (float64, [s]), one unorganised row (height 1), little-endian, dense.
* :func:`from_cloud` (PointCloud2) -> Bead: the inverse (fields found by name, any order or padding; the
  float32 fields come back as float64 arrays).
* :func:`draw_bead` (mujoco.MjvScene, Bead, rgba, world_from_frame=None) -> number of geoms added: the
  bead as capsules along its centre line, each as thick as the bead is wide there (the height is not
  drawn), for off-screen renders. ``BASE_IN_WORLD`` is ur_sim's ``base`` frame in the world for an arm
  at the origin. A gap (points farther apart than ``GAP``) is not bridged. When the scene's geom budget
  is short, every k-th point is drawn.

All conversions go through numpy structured arrays: no per-point Python loops.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the message types are imported where used: the pure model (dispenser.py) needs no ROS
    from builtin_interfaces.msg import Time
    from sensor_msgs.msg import PointCloud2

# ur_sim's ``base`` frame in the MuJoCo world for an arm at the origin (base_link = world; base = Rz(pi)).
BASE_IN_WORLD = np.diag([-1.0, -1.0, 1.0, 1.0])
ASPECT = 1.2  # height / width of the bead's triangular section (a V-cut nozzle's windshield bead: 10 mm x 12 mm)
GAP = 0.005  # [m] consecutive points farther apart than this are drawn unconnected (a gap in the bead)

# The cloud's point layout: 5 float32 then the float64 time, 28 bytes, no padding.
CLOUD_DTYPE = np.dtype([('x', '<f4'), ('y', '<f4'), ('z', '<f4'), ('width', '<f4'), ('height', '<f4'),
                        ('t', '<f8')])
_FLOAT32, _FLOAT64 = 7, 8  # sensor_msgs/PointField datatypes
_FIELD_TYPES = {_FLOAT32: '<f4', _FLOAT64: '<f8'}
_NP_TO_FIELD = {np.dtype('<f4'): _FLOAT32, np.dtype('<f8'): _FLOAT64}


def section(area: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Width and height [m] of the triangular bead section of ``area`` [m^2]: A = w h / 2, h = ASPECT w."""
    w = np.sqrt(2.0 * np.maximum(area, 0.0) / ASPECT)
    return w, ASPECT * w


@dataclass(frozen=True, eq=False)
class Bead:
    """A bead: ``points`` (N, 3) [m], ``widths`` (N,) [m], ``heights`` (N,) [m], ``times`` (N,) [s]."""

    points: np.ndarray
    widths: np.ndarray
    heights: np.ndarray
    times: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.points)
        if np.shape(self.points) != (n, 3):
            raise ValueError(f'points must have shape (N, 3), got {np.shape(self.points)}')
        for name in ('widths', 'heights', 'times'):
            if np.shape(getattr(self, name)) != (n,):
                raise ValueError(f'{name} must have shape ({n},) like points, got {np.shape(getattr(self, name))}')

    @staticmethod
    def empty() -> Bead:
        return Bead(np.zeros((0, 3)), np.zeros(0), np.zeros(0), np.zeros(0))

    def __len__(self) -> int:
        return len(self.points)

    def length(self) -> float:
        """Length of the centre line [m], gaps included."""
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum()) if len(self) > 1 else 0.0


def to_cloud(bead: Bead, frame_id: str, stamp: Time, t_offset: float = 0.0) -> PointCloud2:
    """The bead as a PointCloud2 (fields x, y, z, width, height float32 [m], t float64 [s]); `t_offset` [s] is added to
    every time (the stamps' origin: t is then on the clock of the stamps)."""
    from sensor_msgs.msg import PointCloud2, PointField

    rows = np.empty(len(bead), dtype=CLOUD_DTYPE)
    for axis, name in enumerate('xyz'):
        rows[name] = bead.points[:, axis]
    rows['width'], rows['height'], rows['t'] = bead.widths, bead.heights, bead.times + t_offset
    msg = PointCloud2()
    msg.header.frame_id = frame_id
    msg.header.stamp = stamp
    msg.height, msg.width = 1, len(bead)
    msg.fields = [PointField(name=name, offset=CLOUD_DTYPE.fields[name][1], datatype=_NP_TO_FIELD[dt], count=1)
                  for name, dt in ((n, CLOUD_DTYPE.fields[n][0]) for n in CLOUD_DTYPE.names)]
    msg.is_bigendian = False
    msg.point_step = CLOUD_DTYPE.itemsize
    msg.row_step = CLOUD_DTYPE.itemsize * len(bead)
    msg.is_dense = True
    msg.data = rows.tobytes()
    return msg


def from_cloud(msg: PointCloud2) -> Bead:
    """The bead in a PointCloud2 written by :func:`to_cloud` (or any cloud with those fields).

    Raises:
        ValueError: a field is missing or not float32/float64, or the data is shorter than the header says.
    """
    fields = {f.name: f for f in msg.fields}
    names, formats, offsets = [], [], []
    for name in CLOUD_DTYPE.names:
        f = fields.get(name)
        if f is None:
            raise ValueError(f"PointCloud2 has no field '{name}' (fields: {', '.join(fields) or 'none'})")
        if f.datatype not in _FIELD_TYPES:
            raise ValueError(f"PointCloud2 field '{name}' has datatype {f.datatype}; expected FLOAT32 (7) or "
                             'FLOAT64 (8)')
        code = _FIELD_TYPES[f.datatype]
        names.append(name)
        formats.append(code.replace('<', '>') if msg.is_bigendian else code)
        offsets.append(f.offset)
    n = msg.width * msg.height
    dtype = np.dtype({'names': names, 'formats': formats, 'offsets': offsets, 'itemsize': msg.point_step})
    data = bytes(msg.data) if not isinstance(msg.data, (bytes, bytearray, memoryview)) else msg.data
    if len(data) < n * msg.point_step:
        raise ValueError(f'PointCloud2 data has {len(data)} bytes; {n} points x {msg.point_step} need '
                         f'{n * msg.point_step}')
    rows = np.frombuffer(data, dtype=dtype, count=n)
    points = np.stack([rows['x'], rows['y'], rows['z']], axis=1).astype(float)
    return Bead(points, rows['width'].astype(float), rows['height'].astype(float), rows['t'].astype(float))


def draw_bead(scene, bead: Bead, rgba: Sequence[float] = (0.95, 0.75, 0.1, 1.0),
              world_from_frame: np.ndarray | None = None) -> int:
    """Add the bead to ``scene`` (mujoco.MjvScene) as capsules; returns how many geoms were added.

    Args:
        scene: the scene after ``mjv_updateScene`` / ``Renderer.update_scene`` (geoms are appended).
        bead: the bead, in the frame ``world_from_frame`` (4, 4) places in the MuJoCo world (None: the world
            frame). ur_sim publishes in ``base``, which is the world turned by pi about z when the arm stands
            at the world origin: pass ``BASE_IN_WORLD`` then.
        rgba: colour.
    """
    import mujoco

    if len(bead) == 0:
        return 0
    pts = np.asarray(bead.points, dtype=float)
    if world_from_frame is not None:
        pts = pts @ world_from_frame[:3, :3].T + world_from_frame[:3, 3]
    budget = scene.maxgeom - scene.ngeom
    if budget <= 0:
        return 0
    step = max(1, -(-len(pts) // budget))
    idx = np.arange(0, len(pts), step)
    pts, widths = pts[idx], np.asarray(bead.widths, dtype=float)[idx]
    radius = np.maximum(widths, 1e-4) / 2.0
    colour = np.asarray(rgba, dtype=np.float32)
    added = 0
    if len(pts) == 1:
        segments = [(0, 0)]
    else:
        gaps = np.linalg.norm(np.diff(pts, axis=0), axis=1) > GAP * step
        segments = [(i, i + 1) for i in np.flatnonzero(~gaps)]
        # Points with no connected neighbour (isolated spots) are drawn as spheres.
        connected = np.zeros(len(pts), dtype=bool)
        connected[:-1] |= ~gaps
        connected[1:] |= ~gaps
        segments += [(i, i) for i in np.flatnonzero(~connected)]
    for a, b in segments:
        if scene.ngeom >= scene.maxgeom:
            break
        geom = scene.geoms[scene.ngeom]
        r = max(radius[a], radius[b])
        if a == b:
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_SPHERE, np.array([r, r, r]), pts[a], np.eye(3).ravel(),
                                colour)
        else:
            mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.zeros(9), colour)
            mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, r, pts[a], pts[b])
        scene.ngeom += 1
        added += 1
    return added
