"""The simulated arm as the node sees it: model, physics and low-level control built from a SimConfig."""
from __future__ import annotations

import math
from typing import Protocol

import mujoco
import numpy as np
from scipy.spatial.transform import Rotation

from ur_sim_driver.description.mjcf import (
    FT_FORCE_SENSOR,
    FT_TORQUE_SENSOR,
    PAYLOAD_BODY,
    TCP_ORIENTATION_SENSOR,
    TCP_POSITION_SENSOR,
    add_static_mesh,
    build_mjcf,
)
from ur_sim_driver.description.params import joint_names as model_joint_names
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.scene import pose_matrix, read_scene
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.physics.joint_control import JointControl
from ur_sim_driver.physics.physics import ArmPhysics, ArmState
from ur_sim_driver.physics.servo import JointServo, Setpoint
from ur_sim_driver.physics.tool_contact import FLANGE_LINK, contact_threshold, tool_bodies
from ur_sim_driver.physics.torque_control import PdGains
from ur_sim_driver.robot.direct_torque import DEFAULT_SCALES, FrictionScales, felt_friction
from ur_sim_driver.robot.external_ft import ExternalFtSensor
from ur_sim_driver.robot.io_bank import IoBank
from ur_sim_driver.robot.payload import NO_PAYLOAD, Payload, make_payload
from ur_sim_driver.robot.sim_config import SimConfig

MAX_PHYSICS_STEP = 0.002  # [s] automatic substeps keep the physics step at or below this
# Share of a joint's effort limit the servo plans accelerations with; the rest is margin for the feedback.
EFFORT_SHARE = 0.9
# The servo follows the reference with the type's acceleration limit (5 rad/s^2, MoveIt's conservative value;
# UR publishes none) plus this slack, so that plans made exactly at the limit are passed through unchanged.
ACCEL_SLACK = 1.05
# To stop (at a final point, a hold position or a position limit) the arm brakes harder, up to this multiple
# of that limit where its torques allow (more makes several joints braking at once saturate their torques).
BRAKE_CAPABILITY = 2.0
# Freedrive: the joints' viscous damping is their own inertia over this time constant [s] (light: a push keeps
# the arm moving for about this long). The limits hold with the joint's full effort: it is reached this far above
# the velocity limit [rad/s] and this far past a position limit [rad].
FREEDRIVE_TAU = 0.2
FREEDRIVE_VELOCITY_BAND = 0.05
FREEDRIVE_POSITION_BAND = 0.01


class JointReference(Protocol):
    """What the robot is commanded each control period (a trajectory controller's sample is one)."""

    positions: np.ndarray  # (n,) [rad]
    velocities: np.ndarray  # (n,) [rad/s]
    accelerations: np.ndarray  # (n,) [rad/s^2]


_NO_WRENCH = np.zeros(6)
_NO_WRENCH.flags.writeable = False


class Simulator:
    """Arm physics plus its computed-torque joint controller, for one configuration.

    Interface joint i is model joint i: `cfg.joints` only renames them (a tf_prefix is added where missing).
    """

    def __init__(self, cfg: SimConfig) -> None:
        self.params = load_ur_params(cfg.simulated_ur_type)  # the robot's own, whatever the driver is told
        self.software_version = cfg.software_version  # what the controller runs (URScript's functions depend on it)
        tool = get_tool(cfg.tool)
        self.control_rate = cfg.update_rate or self.params.control_rate
        self.control_dt = 1.0 / self.control_rate
        substeps = cfg.physics_substeps or max(1, math.ceil(self.control_dt / MAX_PHYSICS_STEP - 1e-9))
        # The mount only places the arm in the MuJoCo world (floor, scene); interfaces stay in the base frames.
        mount = pose_matrix(cfg.base_pose[:3], cfg.base_pose[3:]) if any(cfg.base_pose) else None
        self.base_link_in_world = np.eye(4) if mount is None else mount  # (4, 4) where base_link is
        xml = build_mjcf(self.params, tf_prefix=cfg.tf_prefix, tool=tool, base_pose=mount,
                         timestep=self.control_dt / substeps)
        # The scene's bodies and the part scanners over them (read once; the scanners' component casts their beams).
        self.scene_bodies, self.scanners = read_scene(cfg.scene) if cfg.scene != 'empty' else ([], None)
        for name, mesh, pose, collide in self.scene_bodies:
            xml = add_static_mesh(xml, name, mesh, pose, collide=collide)
        self.mjcf = xml
        self.urdf = build_urdf(self.params, tf_prefix=cfg.tf_prefix, tool=tool)
        pre = cfg.tf_prefix
        self.joint_names = tuple(j if j.startswith(pre) else pre + j for j in cfg.joints)
        self.physics = ArmPhysics(xml, model_joint_names(pre), self.control_dt, substeps,
                                  base_body=f'{pre}base', payload_body=pre + PAYLOAD_BODY,
                                  tcp_sensors=(pre + TCP_POSITION_SENSOR, pre + TCP_ORIENTATION_SENSOR),
                                  ft_sensors=(pre + FT_FORCE_SENSOR, pre + FT_TORQUE_SENSOR))
        # A tool contact (the driver's tool contact controller, a URScript program): these bodies, over this force [N].
        self.tool_bodies = tool_bodies(self.physics.model, pre + FLANGE_LINK)
        self.tool_contact_force = contact_threshold(cfg.protective_stop_force)
        q0 = np.array(cfg.initial_positions)
        bad = np.flatnonzero((q0 < self.params.q_min) | (q0 > self.params.q_max))
        if bad.size:
            i = int(bad[0])
            raise ConfigError(f"parameter 'initial_positions' [{i}] = {q0[i]} rad is outside the joint limits "
                              f'[{self.params.q_min[i]:.4f}, {self.params.q_max[i]:.4f}] of {self.joint_names[i]}')
        self.physics.reset(q0)
        self.gains = PdGains.critically_damped(len(q0), self.control_rate)
        self.servo = JointServo(q0, self.control_rate)
        self.a_max = np.full(len(q0), self.params.a_max)
        p = self.params
        self.control = JointControl(self.servo, self.gains, p.v_max, p.effort_max, p.q_min, p.q_max,
                                    effort_share=EFFORT_SHARE * p.effort_max, a_floor=0.05 * self.a_max,
                                    a_follow=ACCEL_SLACK * self.a_max, a_brake=BRAKE_CAPABILITY * self.a_max,
                                    dt=self.control_dt)
        self._servo_active = False  # the servo made the last cycle's setpoint (not freedrive, not before any)
        # The robot's IO (immutable; replaced under the simulation lock, read as one snapshot without it).
        self.io = IoBank()
        self.payload: Payload = NO_PAYLOAD  # what the controller believes is mounted (set_payload)
        self.tcp_offset = np.zeros(6)  # set_tcp: the TCP in tool0 (position [m], rotation vector [rad])
        self._tcp: tuple[np.ndarray, Rotation] | None = None  # the same, ready to compose (None: tool0)
        self.mounted: Payload = NO_PAYLOAD  # what is mounted (the configuration's mounted_payload)
        if cfg.mounted_payload.mass > 0.0:
            self.mount(cfg.mounted_payload)
        self._ft_offset = np.zeros(6)
        # ft_rtde_input_enable: the reading comes from RTDE's external_force_torque (None: the arm's own sensor)
        self.external_ft: ExternalFtSensor | None = None
        self.external_ft_input = np.zeros(6)  # the RTDE input external_force_torque as last written
        # The gravity the robot's controller believes in (set_gravity: anti-gravity in the base frame [m/s^2]);
        # None: the one the arm is under, as a correctly installed robot's.
        self.gravity_belief: np.ndarray | None = None
        # Torque control's friction compensation (friction_model_controller), and the scales whose leftover friction
        # the joints carry now (None: the servo's modes, no Coulomb friction; see direct_torque.py).
        self.friction_scales: FrictionScales = DEFAULT_SCALES
        self._felt_scales: FrictionScales | None = None

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return self.physics.time

    def state(self) -> ArmState:
        """Measured joint state now."""
        return self.physics.state()

    def advance(self, state: ArmState, ref: JointReference, stop: np.ndarray | None = None) -> np.ndarray:
        """Track `ref` from `state` for one control period; return the applied torques (n,) [N m].

        The robot's servo turns the reference into a setpoint within the joint limits (``servo.py``), never
        passing `stop` (n,) [rad]; the computed-torque controller tracks the setpoint.
        """
        self._servo_friction()
        mass, bias = self._dynamics()
        # The joints' reachable accelerations, the servo and the computed torques: one compiled call.
        tau = self.control.torques(mass, bias, state.q, state.qd, ref.positions, ref.velocities,
                                   ref.accelerations, stop)
        self._servo_active = True
        self.physics.step(tau)
        return tau

    @property
    def last_setpoint(self) -> Setpoint | None:
        """The servo's setpoint of the last cycle (None in freedrive and before the first cycle)."""
        return self.control.last_setpoint() if self._servo_active else None

    def advance_free(self, state: ArmState) -> np.ndarray:
        """Freedrive for one control period: torques that cancel gravity and Coriolis (the model's bias) with light
        viscous damping, so that the arm moves under external forces; the limits still hold (velocity above its
        limit and positions beyond a limit are pushed back), within the effort limits. Returns the torques (n,)
        [N m]. The servo restarts from the measured state, so that position control resumes without a jump."""
        p = self.params
        self._servo_friction()
        mass, bias = self._dynamics()
        inertia = np.diag(mass)
        q, qd = state.q, state.qd
        tau = bias - inertia / FREEDRIVE_TAU * qd
        excess = qd - np.clip(qd, -p.v_max, p.v_max)
        tau -= p.effort_max * np.clip(excess / FREEDRIVE_VELOCITY_BAND, -1.0, 1.0)
        beyond = np.minimum(q - p.q_min, 0.0) + np.maximum(q - p.q_max, 0.0)
        tau -= p.effort_max * np.clip(beyond / FREEDRIVE_POSITION_BAND, -1.0, 1.0)
        tau = np.clip(tau, -p.effort_max, p.effort_max)
        self.physics.step(tau)
        after = self.physics.state()
        self.servo.reset(after.q, after.qd)
        self._servo_active = False
        return tau

    def advance_torque(self, state: ArmState, torques: np.ndarray, scales: FrictionScales | None = None) -> np.ndarray:
        """Torque control (direct_torque) for one control period: `torques` (n,) [N m] on top of the robot's gravity
        compensation (:meth:`gravity_compensation`), within the effort limits and without driving a joint past its
        speed limit (as under position control); the joints feel the friction the robot's compensation leaves
        (``direct_torque.felt_friction``; `scales`: this command's compensation, a URScript direct_torque's, else
        :attr:`friction_scales`). Returns the motor torques (n,) [N m]. The servo restarts from the
        measured state, so that position control resumes without a jump."""
        p = self.params
        scales = self.friction_scales if scales is None else scales
        if self._felt_scales is not scales:
            self._felt_scales = scales
            self.physics.set_joint_friction(*felt_friction(p.damping, p.coulomb, scales))
        tau = np.asarray(torques, dtype=float) + self.gravity_compensation()
        # No drive turns its joint past the speed limit within the period, as under position control (there the
        # servo's accelerations are bounded so): per joint, from its own inertia and the model's bias torques.
        mass, bias = self.physics.dynamics()
        inertia = np.diag(mass) / self.control_dt
        hi = np.clip(bias + inertia * (p.v_max - state.qd), -p.effort_max, p.effort_max)
        lo = np.clip(bias - inertia * (p.v_max + state.qd), -p.effort_max, p.effort_max)
        tau = np.clip(tau, lo, hi)
        self.physics.step(tau)
        after = self.physics.state()
        self.servo.reset(after.q, after.qd)
        self._servo_active = False
        return tau

    @property
    def coulomb_cancelled(self) -> bool:
        """The joints' Coulomb friction is left out of the physics (the servo's modes cancel it); under torque
        control the joints feel what the compensation leaves."""
        return self._felt_scales is None

    def _servo_friction(self) -> None:
        """The servo's modes after torque control: the joints' viscous friction, no Coulomb friction (the servo
        cancels it)."""
        if self._felt_scales is not None:
            self._felt_scales = None
            self.physics.set_joint_friction(self.params.damping, np.zeros_like(self.params.coulomb))

    def stopping_point(self, state: ArmState) -> np.ndarray:
        """(n,) where the arm, moving at `state`, comes to rest braking as hard as the robot does (leaving
        freedrive), within the joint limits [rad]."""
        a = BRAKE_CAPABILITY * self.a_max
        return np.clip(state.q + state.qd * np.abs(state.qd) / (2.0 * a), self.params.q_min, self.params.q_max)

    def gravity_compensation(self) -> np.ndarray:
        """(n,) the torques [N m] with which the robot's controller holds the arm up at rest: its model of arm and
        tool with the payload it believes mounted (set_payload), under the gravity it believes in (set_gravity)."""
        g = -self.gravity_belief if self.gravity_belief is not None else self.physics.gravity_in_base()
        tau = self.physics.gravity_torques(g)  # arm, tool and the mounted payload
        believed, mounted = self.payload, self.mounted
        if believed.mass != mounted.mass or not np.array_equal(believed.cog, mounted.cog):
            tau = tau + self.physics.point_gravity_torques(believed.mass, believed.cog, g) \
                - self.physics.point_gravity_torques(mounted.mass, mounted.cog, g)
        return tau

    def _dynamics(self) -> tuple[np.ndarray, np.ndarray]:
        """M(q) and the bias torques as the robot's controller models them: with its believed gravity, which
        differs from the true one after a set_gravity that does not match the mounting."""
        mass, bias = self.physics.dynamics()
        if self.gravity_belief is not None:  # gravity torques are linear in the gravity vector
            bias = bias + self.physics.gravity_torques(-self.gravity_belief - self.physics.gravity_in_base())
        return mass, bias

    def set_gravity(self, anti_gravity: np.ndarray) -> None:
        """The robot's set_gravity (under the simulation lock): `anti_gravity` (3,) [m/s^2] in the base frame, the
        acceleration away from the earth as the robot takes it; it replaces the gravity of the controller's model."""
        self.gravity_belief = np.array(anti_gravity, dtype=float)

    def set_tcp(self, offset: np.ndarray) -> None:
        """The robot's set_tcp (under the simulation lock): the TCP in tool0, position [m] and rotation vector [rad]
        (6,); every interface reports the TCP there from now on (RTDE, primary, /tcp_pose_broadcaster, /tf
        tool0_controller)."""
        offset = np.array(offset, dtype=float)
        if offset.shape != (6,) or not np.all(np.isfinite(offset)):
            raise ConfigError(f'set_tcp: the TCP is 6 finite numbers (x, y, z [m], rx, ry, rz [rad]); got {offset}')
        self.tcp_offset = offset
        self._tcp = None if not offset.any() else (offset[:3].copy(), Rotation.from_rotvec(offset[3:]))

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The TCP (tool0 unless set_tcp moved it) in the base frame: position (3,) [m], quaternion (x, y, z, w),
        w >= 0."""
        position, quat = self.physics.tcp_pose()
        if self._tcp is None:
            return position, quat
        offset, turn = self._tcp
        r = Rotation.from_quat(quat)
        out = (r * turn).as_quat()
        return position + r.apply(offset), (out if out[3] >= 0.0 else -out)

    def tcp_velocity(self) -> np.ndarray:
        """(6,) the TCP's linear [m/s] and angular [rad/s] velocity now, base axes."""
        twist = self.physics.tcp_velocity()
        if self._tcp is None:
            return twist
        lever = Rotation.from_quat(self.physics.tcp_pose()[1]).apply(self._tcp[0])
        return np.concatenate((twist[:3] + np.cross(twist[3:], lever), twist[3:]))

    def tcp_at(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The TCP's position (3,) [m], rotation (3, 3) and twist (6,) at joints `q` moving at `qd`, base frame."""
        position, rotation, twist = self.physics.tcp_at(q, qd)
        if self._tcp is None:
            return position, rotation, twist
        offset, turn = self._tcp
        lever = rotation @ offset
        return (position + lever, rotation @ turn.as_matrix(),
                np.concatenate((twist[:3] + np.cross(twist[3:], lever), twist[3:])))

    def set_payload(self, mass: float, cog: np.ndarray, inertia: np.ndarray) -> None:
        """The robot's set_payload (call under the simulation lock): what the controller believes is mounted.

        It changes nothing physical: the mounted payload is the configuration's (``mounted_payload``); the belief
        is taken off the force-torque reading (:meth:`wrench`), as a UR compensates its sensor with it.

        Args:
            mass: [kg] (0: none).
            cog: (3,) centre of gravity in tool0 [m].
            inertia: (6,) ixx, iyy, izz, ixy, ixz, iyz about the centre of gravity, tool0 axes [kg m^2].

        Raises:
            ConfigError: an invalid value (see ``payload.make_payload``); the payload is unchanged then.
        """
        self.payload = make_payload(mass, cog, inertia)

    def mount(self, payload: Payload) -> None:
        """Physically mount `payload` at the flange (under the simulation lock); the belief is unchanged."""
        moments, quat = payload.principal()
        self.physics.set_payload(payload.mass, payload.cog, moments, quat)
        self.mounted = payload

    def _believed_weight(self) -> np.ndarray:
        """(6,) the force [N] and torque [N m] about tool0, in tool0 axes, that the believed payload's weight
        exerts on the flange, under the gravity the controller believes in."""
        mass = self.payload.mass
        if mass == 0.0:  # every cycle reads the wrench: no payload believed, nothing to take off
            return _NO_WRENCH
        g_base = -self.gravity_belief if self.gravity_belief is not None else self.physics.gravity_in_base()
        _, (x, y, z, w) = self.physics.tcp_pose()  # tool0 in the base frame (unit quaternion)
        gx, gy, gz = (float(v) for v in g_base)
        # F = m R^T g, R the quaternion's rotation matrix, written out in floats (every cycle while a payload is
        # believed: SciPy's Rotation costs 50 us, numpy's small-array calls 25 us)
        fx = mass * ((1 - 2 * (y * y + z * z)) * gx + 2 * (x * y + z * w) * gy + 2 * (x * z - y * w) * gz)
        fy = mass * (2 * (x * y - z * w) * gx + (1 - 2 * (x * x + z * z)) * gy + 2 * (y * z + x * w) * gz)
        fz = mass * (2 * (x * z + y * w) * gx + 2 * (y * z - x * w) * gy + (1 - 2 * (x * x + y * y)) * gz)
        cx, cy, cz = (float(v) for v in self.payload.cog)
        return np.array((fx, fy, fz, cy * fz - cz * fy, cz * fx - cx * fz, cx * fy - cy * fx))

    def raw_wrench(self) -> np.ndarray:
        """(6,) the force-torque sensor's reading before payload compensation and zero, tool0 axes about the tool0
        origin: the arm's own sensor (what tool, mounted payload and contacts exert on it), or the external sensor's
        RTDE input while one is enabled (``external_ft.py``)."""
        if self.external_ft is None:
            return self.physics.wrench()
        return self.external_ft.at_flange(self.external_ft_input)

    def wrench(self) -> np.ndarray:
        """(6,) force [N] and torque [N m] at the flange, in tool0 axes about the tool0 origin (the driver's
        tool0_controller frame), as the robot reports it: :meth:`raw_wrench` less the believed payload's weight
        (set_payload) and less the reading at the last :meth:`zero_ftsensor`."""
        return self.raw_wrench() - self._believed_weight() - self._ft_offset

    def tcp_force(self) -> np.ndarray:
        """(6,) :meth:`wrench` in base axes about the TCP (RTDE ``actual_TCP_force``, ``get_tcp_force``)."""
        x, y, z, w_ = self.physics.tcp_pose()[1]
        r = np.empty(9)
        mujoco.mju_quat2Mat(r, np.array((w_, x, y, z)))  # tool0's axes (SciPy's Rotation: 50 us a call)
        r = r.reshape(3, 3)
        w = self.wrench()
        force, torque = r @ w[:3], r @ w[3:]
        lever = r @ self.tcp_offset[:3]  # from tool0 to the TCP
        return np.concatenate((force, torque - np.cross(lever, force)))

    def zero_ftsensor(self) -> None:
        """Take the current reading as the sensor's zero, as the robot's zero_ftsensor does."""
        self._ft_offset = self.raw_wrench() - self._believed_weight()
