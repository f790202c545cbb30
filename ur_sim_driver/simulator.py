"""The simulated arm as the node sees it: model, physics and low-level control built from a SimConfig."""
from __future__ import annotations

import math

import numpy as np

from ur_sim_driver.description.mjcf import add_static_mesh, build_mjcf
from ur_sim_driver.description.params import joint_names as model_joint_names
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.physics import ArmPhysics, ArmState
from ur_sim_driver.scene import load_scene, pose_matrix
from ur_sim_driver.sim_config import SimConfig
from ur_sim_driver.torque_control import PdGains, computed_torque
from ur_sim_driver.trajectory import TrajectorySample

MAX_PHYSICS_STEP = 0.002  # [s] automatic substeps keep the physics step at or below this


class Simulator:
    """Arm physics plus its computed-torque joint controller, for one configuration.

    Interface joint i is model joint i: `cfg.joints` only renames them (a tf_prefix is added where missing).
    """

    def __init__(self, cfg: SimConfig) -> None:
        self.params = load_ur_params(cfg.ur_type)
        tool = get_tool(cfg.tool)
        self.control_rate = cfg.update_rate or self.params.control_rate
        self.control_dt = 1.0 / self.control_rate
        substeps = cfg.physics_substeps or max(1, math.ceil(self.control_dt / MAX_PHYSICS_STEP - 1e-9))
        # The mount only places the arm in the MuJoCo world (floor, scene); interfaces stay in the base frames.
        mount = pose_matrix(cfg.base_pose[:3], cfg.base_pose[3:]) if any(cfg.base_pose) else None
        xml = build_mjcf(self.params, tf_prefix=cfg.tf_prefix, tool=tool, base_pose=mount,
                         timestep=self.control_dt / substeps)
        if cfg.scene != 'empty':
            for name, mesh, pose, collide in load_scene(cfg.scene):
                xml = add_static_mesh(xml, name, mesh, pose, collide=collide)
        self.mjcf = xml
        self.urdf = build_urdf(self.params, tf_prefix=cfg.tf_prefix, tool=tool)
        pre = cfg.tf_prefix
        self.joint_names = tuple(j if j.startswith(pre) else pre + j for j in cfg.joints)
        self.physics = ArmPhysics(xml, model_joint_names(pre), self.control_dt, substeps,
                                  base_body=f'{pre}base', tcp_site=f'{pre}tool0')
        q0 = np.array(cfg.initial_positions)
        bad = np.flatnonzero((q0 < self.params.q_min) | (q0 > self.params.q_max))
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"parameter 'initial_positions' [{i}] = {q0[i]} rad is outside the joint limits "
                              f'[{self.params.q_min[i]:.4f}, {self.params.q_max[i]:.4f}] of {self.joint_names[i]}')
        self.physics.reset(q0)
        self.gains = PdGains.critically_damped(len(q0), self.control_rate)

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return self.physics.time

    def state(self) -> ArmState:
        """Measured joint state now."""
        return self.physics.state()

    def advance(self, state: ArmState, ref: TrajectorySample) -> np.ndarray:
        """Compute torques tracking `ref` from `state`, apply them for one control period; return them (n,) [N m]."""
        # A cubic or quintic may overshoot its points slightly; never command past the joint limits.
        q_ref = np.clip(ref.positions, self.params.q_min, self.params.q_max)
        mass, bias = self.physics.dynamics()
        tau, _ = computed_torque(mass, bias, state.q, state.qd, q_ref, ref.velocities, ref.accelerations,
                                 self.gains, self.params.effort_max)
        self.physics.step(tau)
        return tau

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """tool0 in the base frame: position (3,) [m], quaternion (x, y, z, w)."""
        return self.physics.tcp_pose()
