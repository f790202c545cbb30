"""Where the part really is: the scanners' profiles fitted to the nominal glass, rigidly and in shape.

The measurement is the cell's laser lines (``/ur_sim/part_scan``): profiles (scanners, beams, 3) [m] in the
planner's world, NaN where a beam saw nothing. Each line crosses a glass edge from outside, so a profile gives

* **face points**: every beam that hit the glass; their residual is the height above the glue face of the part as
  fitted, along the face normal [m];
* **one edge point**: where the hits begin, half a beam spacing before the first hit; its residual is its distance
  inside the part's outline in the panel plane [m] (0 on the edge). The edges fix the in-plane placement, which
  the nearly flat face alone cannot.

The part as fitted is the nominal glass moved by a rigid transform (rotation vector about the glass centre, then a
translation: 6 parameters) and bent by a smooth deviation along the panel's w axis (the monomials
``(u / s)^i (v / s)^j`` of degree 2 and 3, s = 0.5 m: 7 parameters; lower degrees are placement). SciPy's
``least_squares`` fits all 13 at once, face residuals weighted by the scanners' noise and edge residuals by the
beam spacing, with a soft-L1 loss against stray points and a light pull of the shape towards zero where the lines
do not see it. The result says what it found (offsets, rotation, shape, residuals) and gives the fitted part as a
:class:`WindshieldModel`, on which the planner lays the bead.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from ur_glue_planner.scene.part_variation import glass_center
from ur_glue_planner.scene.windshield import WindshieldModel

SHAPE_TERMS = ((2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3))  # (i, j) of (u / s)^i (v / s)^j
SHAPE_SCALE = 0.5  # [m] s
FACE_SIGMA = 1e-4  # [m] weight of a face residual (the scanners' noise, with margin)
EDGE_SIGMA = 1e-4  # [m] weight of an edge residual (half a beam spacing)
SHAPE_PRIOR = 0.01  # [m] a shape coefficient's pull towards 0 (weak: the lines decide where they see)


@dataclass(frozen=True, eq=False)
class Registration:
    """The fitted part.

    Attributes:
        transform: (4, 4) world transform: part pose = transform @ nominal pose.
        center: (3,) [m] the nominal glass centre (the rotation's pivot).
        shape: (7,) [m] coefficients of ``SHAPE_TERMS``.
        face_rms, face_max: [m] residual heights of the face points after the fit.
        edge_rms, edge_max: [m] residual distances of the edge points.
        face_points, edge_points: how many were used.
        model: the fitted part (nominal glass moved and bent).
        face, edges: the measured points used (F, 3), (E, 3) [m], world: what the scanners saw.
    """

    transform: np.ndarray
    center: np.ndarray
    shape: np.ndarray
    face_rms: float
    face_max: float
    edge_rms: float
    edge_max: float
    face_points: int
    edge_points: int
    model: WindshieldModel
    face: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))
    edges: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def offset(self) -> np.ndarray:
        """(3,) [m] how far the glass centre moved."""
        return self.transform[:3, :3] @ self.center + self.transform[:3, 3] - self.center

    @property
    def rotation_deg(self) -> np.ndarray:
        """(3,) [deg] roll, pitch, yaw of the part's turn about the world axes."""
        return Rotation.from_matrix(self.transform[:3, :3]).as_euler('xyz', degrees=True)

    def shape_deviation(self, uv: np.ndarray) -> np.ndarray:
        """The fitted deviation (M,) [m] of the face along w at panel points uv (M, 2)."""
        return _shape_basis(np.atleast_2d(uv)) @ self.shape

    def describe(self) -> dict:
        """What the cell found, for logs and reports [mm, deg]."""
        return {'offset_mm': [round(1e3 * float(x), 3) for x in self.offset],
                'rotation_deg': [round(float(x), 4) for x in self.rotation_deg],
                'face_rms_mm': round(1e3 * self.face_rms, 4), 'face_max_mm': round(1e3 * self.face_max, 4),
                'edge_rms_mm': round(1e3 * self.edge_rms, 4), 'edge_max_mm': round(1e3 * self.edge_max, 4),
                'face_points': self.face_points, 'edge_points': self.edge_points}


def _shape_basis(uv: np.ndarray) -> np.ndarray:
    s = uv / SHAPE_SCALE
    return np.column_stack([s[:, 0] ** i * s[:, 1] ** j for i, j in SHAPE_TERMS])


def split_profiles(profiles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Face points (F, 3) and edge points (E, 3) [m] of profiles (S, N, 3) (NaN: no hit), each line running from
    outside the glass inwards. A line whose first beam already hits, or that hits nothing, has no edge point."""
    face, edges = [], []
    for row in np.asarray(profiles, dtype=float):
        hit = np.all(np.isfinite(row), axis=1)
        if not hit.any():
            continue
        face.append(row[hit])
        first = int(np.argmax(hit))
        if first > 0 and first + 1 < len(row) and hit[first + 1]:
            # the edge lies between the last miss and the first hit: half a spacing before the first hit
            edges.append(row[first] - 0.5 * (row[first + 1] - row[first]))
    return (np.vstack(face) if face else np.zeros((0, 3))), (np.array(edges) if edges else np.zeros((0, 3)))


def _transform(x: np.ndarray, center: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    r = Rotation.from_rotvec(x[:3]).as_matrix()
    t[:3, :3] = r
    t[:3, 3] = center + x[3:6] - r @ center
    return t


def fitted_model(nominal: WindshieldModel, transform: np.ndarray, shape: np.ndarray) -> WindshieldModel:
    """The nominal glass moved by ``transform`` (4, 4) and bent by ``shape`` (7,) [m] (SHAPE_TERMS)."""
    pose = transform @ nominal.pose
    raw = tuple(float(c) / SHAPE_SCALE ** (i + j) for c, (i, j) in zip(shape, SHAPE_TERMS))
    return dataclasses.replace(nominal, exponents=tuple(nominal.exponents) + SHAPE_TERMS,
                               coefficients=tuple(nominal.coefficients) + raw,
                               world_from_local=tuple(tuple(float(v) for v in row) for row in pose.tolist()))


def _residuals(x: np.ndarray, nominal: WindshieldModel, center: np.ndarray, face: np.ndarray,
               edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Face heights (F,) and edge distances (E,) [m] for parameters x (rigid 6 + shape 7)."""
    t = _transform(x, center)
    back = lambda p: (p - t[:3, 3]) @ t[:3, :3]  # noqa: E731 - world -> nominal placement
    uv, foot, normal = nominal.project(back(face))
    height = np.einsum('ij,ij->i', back(face) - foot, normal) - _shape_basis(uv) @ x[6:]
    edge_uv = nominal.project(back(edges))[0] if len(edges) else np.zeros((0, 2))
    return height, nominal.glass.signed_distance(edge_uv) if len(edges) else np.zeros(0)


def register(profiles: np.ndarray, nominal: WindshieldModel) -> Registration:
    """Fit the nominal glass to the measured profiles (S, N, 3) [m]; see the module's description.

    Raises:
        ValueError: too little was seen to fit (fewer than 3 edge points or 50 face points).
    """
    face, edges = split_profiles(profiles)
    if len(edges) < 3 or len(face) < 50:
        raise ValueError(f'the scanners saw {len(edges)} glass edges and {len(face)} points on the glass; the fit '
                         'needs at least 3 edges and 50 points')
    center = glass_center(nominal)

    def weighted(x: np.ndarray) -> np.ndarray:
        height, edge = _residuals(x, nominal, center, face, edges)
        return np.concatenate([height / FACE_SIGMA, edge / EDGE_SIGMA, x[6:] / SHAPE_PRIOR])

    fit = least_squares(weighted, np.zeros(6 + len(SHAPE_TERMS)), loss='soft_l1', f_scale=5.0, x_scale=1e-3,
                        max_nfev=200)
    height, edge = _residuals(fit.x, nominal, center, face, edges)
    transform = _transform(fit.x, center)
    shape = fit.x[6:].copy()
    return Registration(transform=transform, center=center, shape=shape,
                        face_rms=float(np.sqrt(np.mean(height ** 2))), face_max=float(np.abs(height).max()),
                        edge_rms=float(np.sqrt(np.mean(edge ** 2))), edge_max=float(np.abs(edge).max()),
                        face_points=len(face), edge_points=len(edges),
                        model=fitted_model(nominal, transform, shape), face=face, edges=edges)


@dataclass(frozen=True)
class CellLimits:
    """What the cell corrects: beyond these a part is refused, never dispensed on.

    Attributes:
        offset: [m] largest placement error per axis the fixture and the robot's reach allow for.
        rotation_deg: [deg] largest turn per axis.
        face_rms: [m] largest rms of the face residual (a higher one: the part is not the glass the cell knows,
            or a scanner sees something else).
        edge_max: [m] largest edge residual.
        edges: fewest glass edges the scanners must see.
    """

    offset: float = 0.01
    rotation_deg: float = 3.0
    face_rms: float = 2e-4
    edge_max: float = 5e-4
    edges: int = 6


def refusal(found: Registration, limits: CellLimits = CellLimits()) -> str | None:
    """Why the part cannot be dispensed on, or None when the cell corrects it."""
    axes = 'xyz'
    offset, turn = found.offset, found.rotation_deg
    for k in range(3):
        if abs(offset[k]) > limits.offset:
            return (f'the part is {1e3 * offset[k]:+.1f} mm off along {axes[k]}, beyond the '
                    f'{1e3 * limits.offset:.0f} mm the cell corrects')
        if abs(turn[k]) > limits.rotation_deg:
            return (f'the part is turned {turn[k]:+.2f} deg about {axes[k]}, beyond the {limits.rotation_deg:g} deg '
                    'the cell corrects')
    if found.edge_points < limits.edges:
        return f'the scanners saw {found.edge_points} glass edges, fewer than the {limits.edges} the fit needs'
    if found.face_rms > limits.face_rms:
        return (f'the glass does not fit the known part: face residual {1e3 * found.face_rms:.3f} mm rms, limit '
                f'{1e3 * limits.face_rms:.3f} mm')
    if found.edge_max > limits.edge_max:
        return (f'an edge is not where the fitted part has it: {1e3 * found.edge_max:.3f} mm off, limit '
                f'{1e3 * limits.edge_max:.3f} mm')
    return None
