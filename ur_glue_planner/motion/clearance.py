"""Whether a planned motion keeps the arm clear of itself and of the floor.

The check uses the very collision shapes ur_sim simulates (``ur_sim_driver.description.mjcf``: capsules and cylinders
fitted to each type's links, the tool's cylinders, the floor at the base's height), so that a plan the planner
accepts does not end in the simulator's protective stop for a self-contact, and a branch of the arm that would
touch itself is not chosen. The glass is not part of it: the nozzle is meant to reach it.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import mujoco
import numpy as np

from ur_sim_driver.description.mjcf import build_mjcf
from ur_sim_driver.description.params import URParams
from ur_sim_driver.description.tool import ToolDef

_WORLD = 0  # MuJoCo's world body: the floor's


@lru_cache(maxsize=32)
def _model(robot: URParams, tool: ToolDef | None) -> mujoco.MjModel:
    """The compiled collision model of an arm and tool, built once (9 ms of the planner's 40 ms otherwise)."""
    return mujoco.MjModel.from_xml_string(build_mjcf(robot, tool=tool))


@dataclass(frozen=True)
class Touch:
    """The first touching configuration of a motion.

    Attributes:
        index: its sample index.
        parts: the two bodies (link names, or 'the floor').
        depth: penetration [m] (> 0).
    """

    index: int
    parts: tuple[str, str]
    depth: float

    def describe(self) -> str:
        return f'{self.parts[0]} touches {self.parts[1]} ({1e3 * self.depth:.1f} mm deep)'


class Clearance:
    """Self- and floor-contacts of one arm with its tool, at given joint positions.

    Args:
        robot: the arm's parameters.
        tool: the tool on its flange, or None.
    """

    def __init__(self, robot: URParams, tool: ToolDef | None) -> None:
        self._model = _model(robot, tool)
        self._data = mujoco.MjData(self._model)  # one per checker: the model is shared, read only
        self._n = 6

    def _name(self, geom: int) -> str:
        body = int(self._model.geom_bodyid[geom])
        return 'the floor' if body == _WORLD else self._model.body(body).name

    def first_touch(self, q: np.ndarray) -> Touch | None:
        """The first of the configurations q (M, 6) [rad] in which two parts touch, or None."""
        m, d = self._model, self._data
        for k, qk in enumerate(np.asarray(q, dtype=float).reshape(-1, self._n)):
            d.qpos[:self._n] = qk
            mujoco.mj_kinematics(m, d)
            mujoco.mj_collision(m, d)
            if d.ncon == 0:
                continue
            dist = d.contact.dist[:d.ncon]  # the contacts' struct-of-arrays view: no per-contact objects
            i = int(np.argmin(dist))
            if dist[i] < 0.0:
                geom = d.contact.geom[i]
                return Touch(k, (self._name(int(geom[0])), self._name(int(geom[1]))), -float(dist[i]))
        return None
