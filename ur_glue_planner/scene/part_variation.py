"""Windshields as a cell sees them: each part placed a little off and bent a little, from a seed.

A *part* is the nominal glass (:data:`~ur_glue_planner.scene.windshield.DEFAULT_WINDSHIELD` at the job's pose)
changed in two ways, both drawn from ``numpy.random.default_rng((seed, index))``:

* **placement**: a rigid error of the fixture, a translation (x, y, z) and a rotation (roll, pitch, yaw about the
  world axes) about the glass's centre, each uniform within its limit (default +-4 mm, +-1 deg);
* **shape**: a smooth deviation of the glue face along the panel's w axis, a random polynomial of degree 2 to 4
  in the panel coordinates scaled to (-1, 1) over the glass, scaled so that its largest magnitude over the glass
  is an amplitude drawn uniformly in [0, limit] (default 2 mm). Degree >= 2: the constant and linear parts of a
  deviation are a placement, drawn above. The glass stays as thick and its outline in (u, v) stays as it is.

The result is again a :class:`WindshieldModel` (the deviation's monomials appended to the face's), so the mesh, the
collision pieces and every geometric query work on a part as on the nominal glass. Only the simulator's scene is
built from a part; the planner is told nothing of it (it measures, ``registration.py``).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ur_glue_planner.scene.windshield import WindshieldModel
from ur_glue_planner.scene.windshield_pieces import sample_uv

DEGREES = range(2, 5)  # degrees of the shape deviation's terms
SAMPLE_STEP = 0.01  # [m] the glass is sampled this finely to scale the deviation to its amplitude


@dataclass(frozen=True)
class VariationLimits:
    """How far parts vary: placement per axis [m], rotation per axis [deg], shape deviation [m]."""

    placement: float = 0.004
    rotation_deg: float = 1.0
    shape: float = 0.002

    def __post_init__(self) -> None:
        for name, value, top in (('placement', self.placement, 0.05), ('rotation_deg', self.rotation_deg, 10.0),
                                 ('shape', self.shape, 0.02)):
            if not 0.0 <= value <= top:
                raise ValueError(f'variation limit {name} = {value} is outside [0, {top}]')


@dataclass(frozen=True)
class Part:
    """One generated windshield.

    Attributes:
        seed, index: where it came from. offset: (3,) [m] placement error in the world.
        rotation_deg: (3,) [deg] roll, pitch, yaw error about the world axes, about ``center``.
        center: (3,) [m] the nominal glass's centre in the world, the pivot of the rotation.
        shape_amplitude: [m] largest |deviation| of the glue face over the glass.
        nominal, model: the glass as drawn and as it is.
    """

    seed: int
    index: int
    offset: tuple[float, float, float]
    rotation_deg: tuple[float, float, float]
    center: tuple[float, float, float]
    shape_amplitude: float
    nominal: WindshieldModel
    model: WindshieldModel

    @property
    def placement(self) -> np.ndarray:
        """The placement error as a world transform (4, 4): true pose = placement @ nominal pose."""
        return placement_matrix(np.array(self.offset), np.array(self.rotation_deg), np.array(self.center))

    def on_part(self, points: np.ndarray) -> np.ndarray:
        """Points (M, 3) [m] on the nominal glass (world) moved to the same (u, v) on this part's glass."""
        return move_onto(points, self.nominal, self.model)

    def deviation(self, uv: np.ndarray) -> np.ndarray:
        """The shape deviation (M,) [m] of the glue face along w at panel points uv (M, 2)."""
        uv = np.atleast_2d(uv)
        return self.model.height(uv[:, 0], uv[:, 1]) - self.nominal.height(uv[:, 0], uv[:, 1])

    def describe(self) -> dict:
        """The part's numbers, for reports [mm, deg]."""
        return {'seed': self.seed, 'index': self.index,
                'offset_mm': [round(1e3 * x, 4) for x in self.offset],
                'rotation_deg': [round(x, 5) for x in self.rotation_deg],
                'shape_amplitude_mm': round(1e3 * self.shape_amplitude, 4)}


def move_onto(points: np.ndarray, nominal: WindshieldModel, model: WindshieldModel) -> np.ndarray:
    """Points (M, 3) [m] near the ``nominal`` glass (world) moved to the same panel (u, v) on ``model``'s glass,
    keeping their height above the face (along its normal)."""
    uv, foot, normal = nominal.project(points)
    height = np.einsum('ij,ij->i', np.atleast_2d(points) - foot, normal)
    return model.surface_point(uv[:, 0], uv[:, 1]) + height[:, None] * model.surface_normal(uv[:, 0], uv[:, 1])


def placement_matrix(offset: np.ndarray, rotation_deg: np.ndarray, center: np.ndarray) -> np.ndarray:
    """World transform (4, 4): rotate by roll, pitch, yaw [deg] about the world axes through ``center`` [m], then
    translate by ``offset`` [m]."""
    t = np.eye(4)
    r = Rotation.from_euler('xyz', rotation_deg, degrees=True).as_matrix()
    t[:3, :3] = r
    t[:3, 3] = center + offset - r @ center
    return t


def glass_center(model: WindshieldModel) -> np.ndarray:
    """Centre (3,) [m] of the glue face in the world: the surface point over the outline's mean (u, v)."""
    uv = model.outline_uv(0.0, 256).mean(axis=0)
    return model.surface_point(uv[0], uv[1])


def _deviation_terms(model: WindshieldModel, rng: np.random.Generator, amplitude: float
                     ) -> tuple[tuple[tuple[int, int], ...], tuple[float, ...]]:
    """Monomials (i, j) of u, v [m] and their coefficients: a random smooth deviation of largest magnitude
    ``amplitude`` [m] over the glass."""
    corners = np.asarray(model.corners_uv)
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    mid, half = (lo + hi) / 2.0, (hi - lo) / 2.0
    grid = sample_uv(model, SAMPLE_STEP)
    scaled = (grid - mid) / half
    terms = [(i, d - i) for d in DEGREES for i in range(d + 1)]
    coeffs = rng.normal(size=len(terms)) / np.array([math.factorial(d) for d in (i + j for i, j in terms)])
    field = sum(c * scaled[:, 0] ** i * scaled[:, 1] ** j for c, (i, j) in zip(coeffs, terms))
    scale = amplitude / max(float(np.abs(field).max()), 1e-12)
    # the same polynomial in raw u, v: least squares on the monomials up to the top degree is exact for it
    raw = [(i, d - i) for d in range(0, max(DEGREES) + 1) for i in range(d + 1)]
    basis = np.column_stack([grid[:, 0] ** i * grid[:, 1] ** j for i, j in raw])
    solution, *_ = np.linalg.lstsq(basis, scale * field, rcond=None)
    return tuple(raw), tuple(float(c) for c in solution)


def make_part(nominal: WindshieldModel, seed: int, index: int, limits: VariationLimits = VariationLimits()) -> Part:
    """Part ``index`` of the series ``seed``: the nominal glass placed off and bent within ``limits``."""
    rng = np.random.default_rng((int(seed), int(index)))
    offset = rng.uniform(-limits.placement, limits.placement, 3)
    rotation = rng.uniform(-limits.rotation_deg, limits.rotation_deg, 3)
    amplitude = float(rng.uniform(0.0, limits.shape))
    exponents, coefficients = _deviation_terms(nominal, rng, amplitude)
    center = glass_center(nominal)
    pose = placement_matrix(offset, rotation, center) @ nominal.pose
    model = dataclasses.replace(
        nominal, exponents=tuple(nominal.exponents) + exponents,
        coefficients=tuple(nominal.coefficients) + coefficients,
        world_from_local=tuple(tuple(float(x) for x in row) for row in pose.tolist()))
    return Part(seed=int(seed), index=int(index), offset=tuple(float(x) for x in offset),
                rotation_deg=tuple(float(x) for x in rotation), center=tuple(float(x) for x in center),
                shape_amplitude=amplitude, nominal=nominal, model=model)
