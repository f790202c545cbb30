"""End-of-arm tools that can be mounted on ``tool0``: for now the glue dispenser of seed 1.

A tool is one rigid link (``ToolDef.name``) fixed to ``tool0`` plus a massless tip frame
(``ToolDef.tip_name``) fixed to that link; both model builders add them as fixed joints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur_sim_driver.description.params import Origin
from ur_sim_driver.errors import ConfigError

TOOL_CHOICES: tuple[str, ...] = ('none', 'dispenser')


@dataclass(frozen=True)
class Cylinder:
    """Collision cylinder of a tool: ``radius``, ``length`` [m]; its axis is the local z of
    ``origin``, which places the cylinder's centre in the tool link frame."""

    name: str
    radius: float
    length: float
    origin: Origin


@dataclass(frozen=True)
class ToolDef:
    """A rigid tool on ``tool0``.

    Attributes:
        name: link (and frame) name of the tool body.
        mount: tool link frame relative to ``tool0``.
        tip_name: name of the tool centre point frame.
        tip: tip frame relative to the tool link frame.
        mass: [kg].  com: centre of mass (3,) [m] in the tool link frame.
        inertia: (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2] about the com, tool link axes.
        geoms: collision cylinders in the tool link frame.
    """

    name: str
    mount: Origin
    tip_name: str
    tip: Origin
    mass: float
    com: tuple[float, float, float]
    inertia: tuple[float, float, float, float, float, float]
    geoms: tuple[Cylinder, ...]

    def tip_in_tool0(self) -> np.ndarray:
        """Homogeneous transform (4, 4) of the tip frame in ``tool0``."""
        return self.mount.matrix() @ self.tip.matrix()


def _solid_cylinder_y(mass: float, radius: float, length: float) -> tuple[float, ...]:
    """Inertia (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2] of a solid cylinder whose axis is y."""
    across = mass * (3.0 * radius**2 + length**2) / 12.0
    return (across, 0.0, 0.0, 0.5 * mass * radius**2, 0.0, across)


# Seed 1 (MATLAB example): the dispenser body is tool0 rotated by rotationX(-90 deg), and its
# 'dispenserEdge' is the body frame moved by (0.04, -0.195, 0) and turned by rotationX(180 deg).
# Composed: tip = tool0 * (translation (0.04, 0, 0.195), Rx(+90 deg)) (DESIGN.md section 6).
# In the dispenser frame the flange normal (tool0 z) is -y, so the body extends along -y.
_BODY_RADIUS = 0.035   # [m] our choice: a 70 mm cartridge gun body
_BODY_LENGTH = 0.15    # [m]
_NOZZLE_RADIUS = 0.006  # [m]
# The nozzle's last 10 mm are left out of the collision shape so that a bead laid with a
# small stand-off does not register as a collision with the workpiece.
_NOZZLE_FROM, _NOZZLE_TO = 0.12, 0.185  # [m] along -y
# 0.5 kg: a small pneumatic cartridge dispenser (the seed's tool is a massless mesh).
_MASS = 0.5

DISPENSER = ToolDef(
    name='dispenser',
    mount=Origin(rpy=(-math.pi / 2, 0.0, 0.0)),
    tip_name='dispenser_tip',
    tip=Origin((0.04, -0.195, 0.0), (math.pi, 0.0, 0.0)),
    mass=_MASS,
    com=(0.0, -_BODY_LENGTH / 2, 0.0),
    inertia=_solid_cylinder_y(_MASS, _BODY_RADIUS, _BODY_LENGTH),
    geoms=(
        Cylinder('dispenser_body', _BODY_RADIUS, _BODY_LENGTH,
                 Origin((0.0, -_BODY_LENGTH / 2, 0.0), (math.pi / 2, 0.0, 0.0))),
        Cylinder('dispenser_nozzle', _NOZZLE_RADIUS, _NOZZLE_TO - _NOZZLE_FROM,
                 Origin((0.04, -(_NOZZLE_FROM + _NOZZLE_TO) / 2, 0.0), (math.pi / 2, 0.0, 0.0))),
    ),
)

_TOOLS: dict[str, ToolDef | None] = {'none': None, 'dispenser': DISPENSER}


def get_tool(name: str | None) -> ToolDef | None:
    """The tool called ``name`` (``None``, ``''`` or ``'none'``: no tool; case-insensitive).

    Raises:
        ConfigError: ``name`` is not one of ``TOOL_CHOICES``.
    """
    key = name.strip().lower() or 'none' if isinstance(name, str) else ('none' if name is None else None)
    if key not in _TOOLS:
        raise ConfigError(f'tool {name!r} is not supported; choose one of: {", ".join(TOOL_CHOICES)}')
    return _TOOLS[key]
