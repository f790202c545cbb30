"""Laser beams cast onto the scene's parts with MuJoCo, and the noise of a real sensor added to what they see.

The scanners see the parts themselves (the scene bodies they target, e.g. the whole windshield mesh), not the
convex pieces the arm collides with (those stand up to 0.5 mm above the glass): :class:`PartRays` builds a MuJoCo
model of the target meshes alone, placed as in the scene, and casts on it with ``mj_multiRay``, which intersects
a mesh's own triangles. The parts are fixed, so the exact ranges are cast once; every measurement adds fresh
Gaussian noise along each beam (:func:`measure`). What the arm would hide from a scanner is not modelled: a cell
measures the part before the robot moves over it.
"""
from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from ur_sim_driver.description.mjcf import add_static_mesh
from ur_sim_driver.description.part_scan import ProfileScanner

_EMPTY = '<mujoco model="parts"><compiler meshdir="/"/><worldbody/></mujoco>'


class PartRays:
    """The target meshes (name, STL path, 4x4 world pose each) as a MuJoCo model to cast beams on."""

    def __init__(self, parts: list[tuple[str, Path, np.ndarray]]) -> None:
        xml = _EMPTY
        for name, mesh, pose in parts:
            xml = add_static_mesh(xml, name, mesh, pose, collide=False)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, self.data)

    def ranges(self, origin: np.ndarray, beams: np.ndarray, max_range: float) -> np.ndarray:
        """Distance (n,) [m] along each unit beam (n, 3) from ``origin`` (3,) [m] to the first part surface, NaN
        where none is within ``max_range`` [m]."""
        n = len(beams)
        geomid = np.zeros(n, dtype=np.int32)
        dist = np.zeros(n)
        mujoco.mj_multiRay(self.model, self.data, np.asarray(origin, dtype=float),
                           np.ascontiguousarray(beams, dtype=float).ravel(), None, 1, -1, geomid, dist, None, n,
                           float(max_range))
        return np.where((dist >= 0.0) & (dist <= max_range), dist, np.nan)

    def profile(self, unit: ProfileScanner, max_range: float) -> tuple[np.ndarray, np.ndarray]:
        """The exact profile of one scanner: beam directions (points, 3) and ranges (points,) [m] (NaN: nothing)."""
        beams = unit.beams()
        return beams, self.ranges(np.asarray(unit.origin), beams, max_range)


def measure(origin: np.ndarray, beams: np.ndarray, ranges: np.ndarray, noise: float,
            rng: np.random.Generator) -> np.ndarray:
    """Points (n, 3) [m] a sensor reports: each exact range plus N(0, noise^2) along its beam; NaN rows where the
    beam saw nothing."""
    measured = ranges + rng.normal(0.0, noise, len(ranges)) if noise > 0.0 else ranges
    return np.asarray(origin)[None, :] + measured[:, None] * beams
