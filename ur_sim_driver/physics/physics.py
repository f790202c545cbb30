"""MuJoCo stepping of a UR arm: indices resolved once by name, torques in, joint state, TCP pose and the
flange's force-torque sensor out; the payload's mass properties changed at run time."""
from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.physics.mj_readout import read_dynamics, read_joints, read_pose


@dataclass(frozen=True)
class Contact:
    """One contact the robot takes part in.

    Attributes:
        robot_part: the robot's body (link or tool) in contact.
        other: the other body, or the scene geom (e.g. 'floor') for bodies fixed to the world.
        force: magnitude of the contact force [N] (normal and friction).
        depth: penetration [m] (>= 0; MuJoCo's soft contacts let bodies overlap slightly).
    """

    robot_part: str
    other: str
    force: float
    depth: float


@dataclass(frozen=True, eq=False)
class ArmState:
    """Measured state of the arm joints.

    Attributes:
        t: simulated time [s].
        q: (n,) positions [rad].
        qd: (n,) velocities [rad/s].
        effort: (n,) joint torques applied by the actuators in the last step [N m].
    """

    t: float
    q: np.ndarray
    qd: np.ndarray
    effort: np.ndarray




def _as_slice(index: list[int]) -> slice | np.ndarray:
    """`index` as a slice when it is a run of consecutive integers, else as an index array."""
    if index and index == list(range(index[0], index[0] + len(index))):
        return slice(index[0], index[0] + len(index))
    return np.array(index, dtype=np.intp)


class ArmPhysics:
    """A MuJoCo model of one arm, stepped at `control_dt` in `substeps` physics steps.

    Args:
        mjcf_xml: the scene (arm, tool, static bodies) as MJCF.
        joint_names: names of the arm joints in controller order (also the actuator names).
        control_dt: control period [s].
        substeps: physics steps per control period; the physics timestep is control_dt / substeps.
        base_body: the body of the UR `base` frame.
        tcp_sensors: names of the framepos and the framequat sensor of the TCP (tool0) in the base frame.
        payload_body: massless body fixed at tool0 whose mass properties :meth:`set_payload` sets.
        ft_sensors: names of the force and the torque sensor at the tool0 site.
    """

    def __init__(self, mjcf_xml: str, joint_names: tuple[str, ...], control_dt: float, substeps: int,
                 base_body: str, tcp_sensors: tuple[str, str], payload_body: str, ft_sensors: tuple[str, str]) -> None:
        self.model = mujoco.MjModel.from_xml_string(mjcf_xml)
        self.model.opt.timestep = control_dt / substeps
        self.data = mujoco.MjData(self.model)
        self.control_dt = control_dt
        self.substeps = substeps
        self.joint_names = tuple(joint_names)
        m = self.model

        def lookup(kind: mujoco.mjtObj, name: str, what: str) -> int:
            idx = mujoco.mj_name2id(m, kind, name)
            if idx < 0:
                raise ConfigError(f"{what} '{name}' is not in the MuJoCo model")
            return idx

        jids = [lookup(mujoco.mjtObj.mjOBJ_JOINT, j, 'joint') for j in joint_names]
        # Index arrays become slices where the addresses are consecutive (the usual case): slicing is about
        # three times cheaper than fancy indexing, and these are read several times every control cycle.
        self._qpos = _as_slice([int(m.jnt_qposadr[j]) for j in jids])
        self._dof = _as_slice([int(m.jnt_dofadr[j]) for j in jids])
        self._act = _as_slice([self._actuator_for(j) for j in jids])
        self._base = lookup(mujoco.mjtObj.mjOBJ_BODY, base_body, 'body')
        self._mass = np.zeros((m.nv, m.nv))
        self._payload = lookup(mujoco.mjtObj.mjOBJ_BODY, payload_body, 'body')
        sensors = [lookup(mujoco.mjtObj.mjOBJ_SENSOR, s, 'sensor') for s in ft_sensors]
        self._ft = _as_slice([int(m.sensor_adr[s]) + k for s in sensors for k in range(3)])
        position, orientation = (int(m.sensor_adr[lookup(mujoco.mjtObj.mjOBJ_SENSOR, s, 'sensor')])
                                 for s in tcp_sensors)
        self._tcp_position, self._tcp_orientation = slice(position, position + 3), slice(orientation, orientation + 4)
        # The site the TCP sensors measure (tool0), for its velocity.
        self._tcp_site = int(m.sensor_objid[lookup(mujoco.mjtObj.mjOBJ_SENSOR, tcp_sensors[0], 'sensor')])
        self._velocity6 = np.zeros(6)
        self._scratch: mujoco.MjData | None = None  # for tcp_at, made when first needed
        # Per geom, once: which belong to the robot (the subtree of the base body's root, i.e. arm and tool)
        # and the name a contact report uses (the body, or the geom for bodies fixed to the world).
        root = int(m.body_rootid[self._base])
        self._robot_geom = m.body_rootid[m.geom_bodyid] == root
        geom_label = [
            mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, int(b)) if b != 0
            else (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f'geom {g}')
            for g, b in enumerate(m.geom_bodyid)]
        # Contacts are summed per pair of labels: the labels numbered once, each geom mapped to its number.
        self._labels = list(dict.fromkeys(geom_label))
        self._geom_label_id = [self._labels.index(label) for label in geom_label]
        self._force6 = np.zeros(6)
        # What the last control period's completed physics steps measured (contacts, flange wrench), averaged over
        # its substeps (see step()).
        self._contacts: tuple[Contact, ...] = ()
        self._wrench = np.zeros(6)
        # MjData's arrays, fetched once: each attribute access builds a new array object (about 0.5 us), and the
        # loop reads a dozen of them every cycle. The arrays share MjData's memory, which never moves.
        d = self.data
        self._d_qpos, self._d_qvel, self._d_ctrl = d.qpos, d.qvel, d.ctrl
        self._d_actuator_force, self._d_bias, self._d_passive = d.actuator_force, d.qfrc_bias, d.qfrc_passive
        self._d_sensordata = d.sensordata
        # The readout kernels (mj_readout.py) take index arrays.
        self._i_qpos = np.array([int(m.jnt_qposadr[j]) for j in jids], dtype=np.int64)
        self._i_dof = np.array([int(m.jnt_dofadr[j]) for j in jids], dtype=np.int64)
        self._i_act = np.array([self._actuator_for(j) for j in jids], dtype=np.int64)
        # The arm's moving part (first joint's body and everything it carries: links, tool, payload).
        self._arm_root = int(m.jnt_bodyid[jids[0]])
        self._jac = np.zeros((3, m.nv))

    def _actuator_for(self, joint_id: int) -> int:
        m = self.model
        for a in range(m.nu):
            if m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and m.actuator_trnid[a, 0] == joint_id:
                return a
        raise ConfigError(f"joint '{mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_JOINT, joint_id)}' "
                          'has no actuator in the MuJoCo model')

    def reset(self, q: np.ndarray) -> None:
        """Put the arm at rest at `q` (n,) [rad], time 0."""
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self._qpos] = q
        mujoco.mj_forward(self.model, self.data)
        # mj_forward has solved the constraints of this state: its contacts and sensor readings belong together.
        forces, depths = {}, {}
        self._collect(forces, depths)
        self._contacts = self._mean(forces, depths, 1)
        self._wrench = -self._d_sensordata[self._ft]
        mujoco.mj_step1(self.model, self.data)

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def state(self) -> ArmState:
        """The arm's measured state now."""
        out = np.empty((3, len(self._i_qpos)))
        read_joints(self._d_qpos, self._d_qvel, self._d_actuator_force, self._i_qpos, self._i_dof, self._i_act, out)
        return ArmState(self.data.time, out[0], out[1], out[2])

    def positions(self) -> np.ndarray:
        """(n,) joint positions now [rad]."""
        return self._d_qpos[self._qpos].copy()

    def gravity_in_base(self) -> np.ndarray:
        """(3,) the gravitational acceleration [m/s^2] the arm is under, in the base frame."""
        return self.data.xmat[self._base].reshape(3, 3).T @ self.model.opt.gravity

    def gravity_torques(self, g_base: np.ndarray) -> np.ndarray:
        """(n,) joint torques [N m] that hold the arm, tool and payload still at the current positions under a
        gravitational acceleration `g_base` (3,) [m/s^2] in the base frame."""
        m, d = self.model, self.data
        g_world = d.xmat[self._base].reshape(3, 3) @ np.asarray(g_base, dtype=float)
        mujoco.mj_jacSubtreeCom(m, d, self._jac, self._arm_root)
        return -float(m.body_subtreemass[self._arm_root]) * (self._jac[:, self._i_dof].T @ g_world)

    def coriolis_torques(self) -> np.ndarray:
        """(n,) the Coriolis and centrifugal torques [N m] at the current state: MuJoCo's bias forces less
        gravity's."""
        return self._d_bias[self._i_dof] - self.gravity_torques(self.gravity_in_base())

    def point_gravity_torques(self, mass: float, point: np.ndarray, g_base: np.ndarray) -> np.ndarray:
        """(n,) joint torques [N m] that hold a point mass `mass` [kg] carried by the flange at `point` (3,) [m] in
        tool0 still under a gravitational acceleration `g_base` (3,) [m/s^2] in the base frame (the arm's own
        weight is not in it)."""
        m, d = self.model, self.data
        site = self._tcp_site
        where = d.site_xpos[site] + d.site_xmat[site].reshape(3, 3) @ np.asarray(point, dtype=float)
        g_world = d.xmat[self._base].reshape(3, 3) @ np.asarray(g_base, dtype=float)
        mujoco.mj_jac(m, d, self._jac, None, where, int(m.site_bodyid[site]))
        return -mass * (self._jac[:, self._i_dof].T @ g_world)

    def set_joint_friction(self, damping: np.ndarray, coulomb: np.ndarray) -> None:
        """The joints' viscous friction `damping` (n,) [N m s/rad] and Coulomb friction `coulomb` (n,) [N m], from
        the next step on. MuJoCo treats both implicitly (damping in the integrator, Coulomb friction as a
        constraint), so a joint with little inertia stays stable at the control period."""
        self.model.dof_damping[self._dof] = damping
        self.model.dof_frictionloss[self._dof] = coulomb
        # The invariant of step(): the passive forces of the current state follow the new damping.
        mujoco.mj_step1(self.model, self.data)

    def dynamics(self) -> tuple[np.ndarray, np.ndarray]:
        """M(q) (n, n) [kg m^2] and h(q, qd) = gravity + Coriolis - passive (n,) [N m] at the current state."""
        mujoco.mj_fullM(self.model, self.data, self._mass)
        n = len(self._i_dof)
        mass, bias = np.empty((n, n)), np.empty(n)
        read_dynamics(self._mass, self._d_bias, self._d_passive, self._i_dof, mass, bias)
        return mass, bias

    def step(self, tau: np.ndarray) -> None:
        """Apply joint torques `tau` (n,) [N m] for one control period (zero-order hold).

        Contacts and the flange's wrench are measured from each completed physics step (after mj_step2, whose
        constraint forces, contacts and force-torque sensors belong to the state that step started from) and
        averaged over the period's substeps: a robot's sensors see the period, not the solver's last iterate.
        """
        # Invariant between calls: mj_step1 has run for the current state, so M, h and the TCP pose
        # read by the caller are those of the state the next torques act on.
        self._d_ctrl[self._act] = tau
        m, d = self.model, self.data
        wrench = np.zeros(6)
        forces: dict[tuple[int, int], np.ndarray] = {}
        depths: dict[tuple[int, int], float] = {}
        for _ in range(self.substeps):
            mujoco.mj_step2(m, d)
            wrench -= self._d_sensordata[self._ft]
            if d.ncon:
                self._collect(forces, depths)
            mujoco.mj_step1(m, d)
        self._wrench = wrench / self.substeps
        self._contacts = self._mean(forces, depths, self.substeps) if forces else ()

    def _collect(self, forces: dict, depths: dict) -> None:
        """Add this step's contact forces of the robot (world frame [N]) per pair of bodies to `forces`, and the
        deepest penetration [m] per pair to `depths` (contacts and efc_force of one solved step)."""
        d = self.data
        for i in range(d.ncon):
            c = d.contact[i]
            g1, g2 = int(c.geom1), int(c.geom2)
            r1, r2 = self._robot_geom[g1], self._robot_geom[g2]
            if not (r1 or r2):
                continue  # two scene bodies
            mujoco.mj_contactForce(self.model, d, i, self._force6)
            # The contact frame's rows are its normal and two tangents: its transpose maps the force to world axes.
            f = c.frame.reshape(3, 3).T @ self._force6[:3]
            key = (self._geom_label_id[g1], self._geom_label_id[g2]) if r1 else \
                (self._geom_label_id[g2], self._geom_label_id[g1])
            if key in forces:
                forces[key] = forces[key] + f
                depths[key] = max(depths[key], -float(c.dist))
            else:
                forces[key], depths[key] = f, -float(c.dist)

    def _mean(self, forces: dict, depths: dict, steps: int) -> tuple[Contact, ...]:
        labels = self._labels
        return tuple(Contact(labels[a], labels[b], float(np.linalg.norm(f)) / steps, max(0.0, depths[a, b]))
                     for (a, b), f in forces.items())

    def contacts(self) -> tuple[Contact, ...]:
        """Contacts of the robot (arm and tool) with the scene or itself over the last control period: one per pair
        of bodies, its force the magnitude of the pair's total contact force averaged over the period's physics
        steps [N], its depth the deepest penetration seen [m]."""
        return self._contacts

    def tcp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """TCP pose in the base frame: position (3,) [m] and quaternion (4,) as (x, y, z, w), w >= 0 (as the
        driver's, which builds it from an axis and an angle in [0, pi])."""
        pose = np.empty(7)
        read_pose(self._d_sensordata, self._tcp_position.start, self._tcp_orientation.start, pose)
        return pose[:3], pose[3:]

    def tcp_at(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The TCP (tool0) at joint positions `q` (n,) [rad] and velocities `qd` (n,) [rad/s], the rest of the state
        as now, computed in a scratch copy of the data (the simulation is untouched): position (3,) [m] and rotation
        matrix (3, 3) in the base frame, and its twist (6,) (linear [m/s], angular [rad/s]) in base axes."""
        m = self.model
        if self._scratch is None:
            self._scratch = mujoco.MjData(m)
        d = self._scratch
        d.qpos[:] = self.data.qpos
        d.qvel[:] = 0.0
        d.qpos[self._qpos] = q
        d.qvel[self._dof] = qd
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        r_base, p_base = d.xmat[self._base].reshape(3, 3), d.xpos[self._base]
        position = r_base.T @ (d.site_xpos[self._tcp_site] - p_base)
        rotation = r_base.T @ d.site_xmat[self._tcp_site].reshape(3, 3)
        twist = np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, self._tcp_site, twist, 0)
        return position, rotation, np.concatenate((r_base.T @ twist[3:], r_base.T @ twist[:3]))

    def tcp_velocity(self) -> np.ndarray:
        """(6,) the TCP's linear [m/s] and angular [rad/s] velocity now, in base axes (the base is fixed)."""
        # mj_step1 has computed the velocities of the current state (the invariant of step()).
        mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_SITE, self._tcp_site, self._velocity6, 0)
        r_base = self.data.xmat[self._base].reshape(3, 3)  # world axes -> base axes: its transpose
        angular, linear = self._velocity6[:3], self._velocity6[3:]
        return np.concatenate((r_base.T @ linear, r_base.T @ angular))

    def body_motion(self, body: int) -> tuple[np.ndarray, np.ndarray]:
        """The origin of body `body` (a MuJoCo id) now: position (3,) [m] and linear velocity (3,) [m/s], base frame."""
        d = self.data
        r_base = d.xmat[self._base].reshape(3, 3)
        mujoco.mj_objectVelocity(self.model, d, mujoco.mjtObj.mjOBJ_BODY, body, self._velocity6, 0)
        return r_base.T @ (d.xpos[body] - d.xpos[self._base]), r_base.T @ self._velocity6[3:]

    def wrench(self) -> np.ndarray:
        """(6,) force [N] and torque [N m] that the bodies beyond tool0 (tool, payload) exert on the arm,
        about the tool0 origin, in tool0 axes, averaged over the last control period's physics steps.

        MuJoCo's force and torque sensors give the opposite: what the parent (the arm) exerts on the
        sensor's body and its subtree. Weight, contacts and the subtree's inertia all appear in it.
        """
        return self._wrench.copy()

    def body_id(self, name: str) -> int | None:
        """The MuJoCo id of body `name`, or None when the model has no such body."""
        idx = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, name)
        return idx if idx >= 0 else None

    def set_external_wrench(self, body: int, force: np.ndarray, torque: np.ndarray) -> None:
        """Push body `body` (an id) with `force` (3,) [N] and `torque` (3,) [N m], given in the base frame and
        acting at the body's centre of mass, from the next step on until changed (zeros remove it)."""
        r_base = self.data.xmat[self._base].reshape(3, 3)
        self.data.xfrc_applied[body, :3] = r_base @ np.asarray(force, dtype=float)
        self.data.xfrc_applied[body, 3:] = r_base @ np.asarray(torque, dtype=float)

    def set_payload(self, mass: float, cog: np.ndarray, moments: np.ndarray, quat: np.ndarray) -> None:
        """Give the payload body `mass` [kg] with its centre at `cog` (3,) [m] in tool0 and principal
        moments `moments` (3,) [kg m^2] along axes oriented by `quat` (w, x, y, z) in tool0."""
        m, b = self.model, self._payload
        m.body_mass[b] = mass
        m.body_ipos[b] = cog
        m.body_inertia[b] = moments
        m.body_iquat[b] = quat
        # Derived model constants (subtree masses, inverse weights used by the constraint solver, whether
        # the inertial frame equals the body frame) follow the new values only through mj_setConst. It
        # evaluates the model at qpos0 in the data it is given: a scratch one, so the state is untouched.
        mujoco.mj_setConst(m, mujoco.MjData(m))
        # The invariant of step(): M, h and the poses are those of the current state (now with the payload).
        mujoco.mj_step1(m, self.data)
