"""Can the tip be put at a taught waypoint? IK, joint limits and collisions with the glass, with a reason.

For the selected waypoint the studio shows the robot at :func:`Reach.solve`'s joint positions; a waypoint that is
unreachable is drawn red with ``reason``:

- no IK solution: no joint positions put the tip there, even ignoring the joint limits;
- joint limit: a solution exists only outside the limits (the joint, its value and the limit are named);
- collision with the glass: every solution found puts a robot or tool body into the glass (MuJoCo's contacts
  against the windshield's convex collision pieces, the simulator's own geometry; the nozzle's last 10 mm are not a
  collision body, so a bead at zero stand-off does not count).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from ur_glue_planner.motion.ik_branch import start_branches
from ur_glue_planner.motion.kinematics import Kinematics
from ur_sim_driver.description.mjcf import add_static_mesh, build_mjcf
from ur_sim_driver.description.params import URParams, joint_names
from ur_sim_driver.description.tool import ToolDef


@dataclass(frozen=True)
class ReachResult:
    """IK at one waypoint: joint positions q (n,) [rad] (best effort when not reachable), reachable, reason."""

    q: np.ndarray
    reachable: bool
    reason: str


class GlassCollision:
    """Robot (with tool) and the windshield's collision pieces in MuJoCo, for contact queries at given q.

    Args:
        robot, tool: The arm's parameters and its tool.
        pieces: (STL path, world pose (4, 4)) of each convex glass piece.
    """

    def __init__(self, robot: URParams, tool: ToolDef | None, pieces: list[tuple[Path, np.ndarray]]) -> None:
        xml = build_mjcf(robot, tool=tool)
        for k, (stl, pose) in enumerate(pieces):
            xml = add_static_mesh(xml, f'glass_{k:02d}', stl, pose, collide=True)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self._qadr = [self.model.jnt_qposadr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, n)]
                      for n in joint_names()]
        glass_bodies = {mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, f'glass_{k:02d}')
                        for k in range(len(pieces))}
        self._is_glass = np.array([b in glass_bodies for b in self.model.geom_bodyid])

    def contacts(self, q: np.ndarray) -> list[tuple[str, float]]:
        """(robot body name, penetration depth [m]) of every contact with the glass at joint positions q (6,)."""
        self.data.qpos[self._qadr] = q
        mujoco.mj_forward(self.model, self.data)
        out = []
        for c in self.data.contact[:self.data.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if self._is_glass[g1] == self._is_glass[g2]:
                continue
            robot = g2 if self._is_glass[g1] else g1
            body = mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, int(self.model.geom_bodyid[robot]))
            out.append((body, float(-c.dist)))
        return out


class Reach:
    """Reachability of tip poses for one arm.

    Args:
        kin: Tip kinematics (its joint limits apply).
        collision: Glass contacts, or None to skip that check.
    """

    def __init__(self, kin: Kinematics, collision: GlassCollision | None) -> None:
        self.kin = kin
        self.collision = collision
        # The same arm without joint limits: tells "no solution" from "only outside the limits".
        self._free = copy.copy(kin)
        self._free.data = kin.model.createData()
        self._free.q_min = np.full(kin.n, -1e3)
        self._free.q_max = np.full(kin.n, 1e3)

    def _collision_reason(self, q: np.ndarray) -> str:
        if self.collision is None:
            return ''
        hits = self.collision.contacts(q)
        if not hits:
            return ''
        body, depth = max(hits, key=lambda h: h[1])
        return f'collision with the glass: {body} {depth * 1e3:.1f} mm into it'

    def solve(self, target: np.ndarray, q_ref: np.ndarray) -> ReachResult:
        """Joint positions for the tip at ``target`` (4, 4) [m], nearest to ``q_ref`` (6,) [rad] among those found.

        Tries a warm start from ``q_ref`` first, then every IK branch (fixed guesses, repeatable).
        """
        q_ref = np.asarray(q_ref, dtype=float)
        first = self.kin.ik(target, q_ref)
        if first.converged and not self._collision_reason(first.q):
            return ReachResult(first.q, True, '')
        candidates = sorted(start_branches(self.kin, target, q_ref), key=lambda q: float(np.linalg.norm(q - q_ref)))
        for q in candidates:
            if not self._collision_reason(q):
                return ReachResult(q, True, '')
        if candidates:
            return ReachResult(candidates[0], False, self._collision_reason(candidates[0]))
        free = self._free.ik(target, q_ref)
        if not free.converged:
            free_q = start_branches(self._free, target, q_ref)
            if not free_q:
                return ReachResult(first.q, False, f'no IK solution: out of reach (residual '
                                   f'{first.residual_pos * 1e3:.1f} mm, {np.degrees(first.residual_rot):.1f} deg)')
            q_free = free_q[0]
        else:
            q_free = free.q
        over = np.maximum(self.kin.q_min - q_free, q_free - self.kin.q_max)
        j = int(np.argmax(over))
        return ReachResult(first.q, False, f'joint limit: {self.kin.joint_names[j]} would need {q_free[j]:.2f} rad, '
                                           f'limits [{self.kin.q_min[j]:.2f}, {self.kin.q_max[j]:.2f}]')


def waypoint_pose(position, rotation: np.ndarray, normal=None, standoff: float = 0.0) -> np.ndarray:
    """Tip pose (4, 4) at a waypoint: ``position`` [m] moved ``standoff`` [m] along the glass ``normal``."""
    pose = np.eye(4)
    pose[:3, :3] = rotation
    pose[:3, 3] = np.asarray(position, dtype=float) + (standoff * np.asarray(normal) if standoff else 0.0)
    return pose
