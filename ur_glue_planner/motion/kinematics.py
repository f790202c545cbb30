"""Forward, differential and inverse kinematics of one frame of an arm, with Pinocchio.

The model comes from a URDF string (``ur_sim_driver.description.urdf.build_urdf``, whose root
is ``base_link``). An optional ``base_pose`` places ``base_link`` in a world frame: every pose,
Jacobian and IK target of this class is then expressed in that world. All twists are
LOCAL_WORLD_ALIGNED and ordered linear then angular: ``(v_origin [m/s], omega [rad/s])``,
the velocity of the frame's origin and its angular velocity, both in world axes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.spatial.transform import Rotation

from ur_glue_planner.errors import PlanningError

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")


@dataclass(frozen=True)
class IkResult:
    """Outcome of :meth:`Kinematics.ik`.

    Attributes:
        q: Joint positions (n,) [rad], in the order of ``Kinematics.joint_names``.
        residual_pos: Distance [m] between the reached and the target frame origin.
        residual_rot: Angle [rad] of the rotation between reached and target frame.
        iterations: Gauss-Newton steps taken.
        converged: Both residuals (those with a non-zero weight) within tolerance.
    """

    q: np.ndarray
    residual_pos: float
    residual_rot: float
    iterations: int
    converged: bool


@dataclass(frozen=True, eq=False)
class PathIk:
    """Outcome of :meth:`Kinematics.ik_path`: IK of a sequence of poses along a path.

    Attributes:
        q: (M, n) [rad]; rows from ``failed`` on are not solutions (NaN past it).
        residual_pos: (M,) [m]; residual_rot: (M,) [rad]; iterations: (M,) Newton steps per sample.
        failed: Index of the first pose that IK could not reach (its residuals are those of the
            last attempt), or None.
        position, rotation, jacobian: FK (M, 3), (M, 3, 3) and LWA Jacobians (M, 6, n) at q up to
            ``failed``, when the solver computed them anyway (else None).
    """

    q: np.ndarray
    residual_pos: np.ndarray
    residual_rot: np.ndarray
    iterations: np.ndarray
    failed: int | None
    position: np.ndarray | None = None
    rotation: np.ndarray | None = None
    jacobian: np.ndarray | None = None


def pose_errors(targets: np.ndarray, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position error [m] and rotation angle [rad] (M,) between target poses (M, 4, 4) and (M, 3), (M, 3, 3)."""
    rel = Rotation.from_matrix(targets[:, :3, :3]) * Rotation.from_matrix(rotation).inv()
    return np.linalg.norm(targets[:, :3, 3] - position, axis=1), rel.magnitude()


def serial_drift(jac: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """dJ/dt qd (M, 6) of revolute joints in chain order, from their LWA Jacobians (M, 6, n) alone.

    Column i of the Jacobian is (v_i, w_i): w_i the joint axis, v_i = w_i x (p - o_i). Turning
    joint k moves column i by w_k x (v_i, w_i) for k <= i (both turn with joint k) and by
    (w_i x v_k, 0) for k > i (only the frame origin p moves), so with the partial sums
    W_i = sum_{k<=i} qd_k w_k and V_i = sum_{k<=i} qd_k v_k:
    dw_i/dt = W_i x w_i and dv_i/dt = W_i x v_i + w_i x (V_n - V_i).
    """
    v, w, qd = jac[:, :3], jac[:, 3:], qd[:, None, :]  # (M, 3, n), (M, 3, n), (M, 1, n)
    big_w = np.cumsum(w * qd, axis=2)
    big_v = np.cumsum(v * qd, axis=2)
    v_dot = _cross(big_w, v) + _cross(w, big_v[:, :, -1:] - big_v)
    w_dot = _cross(big_w, w)
    return np.concatenate([(v_dot * qd).sum(axis=2), (w_dot * qd).sum(axis=2)], axis=1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products over axis 1 of (M, 3, n) arrays (np.cross wants the vectors last)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], axis=1)


class Kinematics:
    """Kinematics of ``frame`` as a function of the named joints.

    Args:
        urdf: URDF XML string.
        joint_names: Revolute joints (n,) in the order q is given in; resolved once by name.
        frame: Frame whose pose is computed, e.g. 'dispenser_tip', 'tool0', 'ee_link'.
        base_pose: World-from-root pose (4, 4) of the URDF root; identity if None.

    Raises:
        ValueError: An unknown joint or frame name, or a malformed base_pose.

    One instance holds one Pinocchio ``Data`` workspace: do not share it between threads.
    """

    def __init__(self, urdf: str, joint_names: Sequence[str], frame: str,
                 base_pose: np.ndarray | None = None) -> None:
        self.model = pin.buildModelFromXML(urdf)
        self.data = self.model.createData()
        self.joint_names = tuple(joint_names)
        self.frame = frame
        if not self.model.existFrame(frame):
            names = sorted({f.name for f in self.model.frames})
            raise ValueError(f"frame {frame!r} is not in the model; frames: {', '.join(names)}")
        self.frame_id = self.model.getFrameId(frame)
        idx_q, idx_v = [], []
        for name in self.joint_names:
            if not self.model.existJointName(name):
                raise ValueError(f"joint {name!r} is not in the model")
            joint = self.model.joints[self.model.getJointId(name)]
            if joint.nq != 1 or joint.nv != 1:
                raise ValueError(f"joint {name!r} is not a 1-dof joint")
            idx_q.append(joint.idx_q)
            idx_v.append(joint.idx_v)
        self._idx_q = np.array(idx_q)
        self._idx_v = np.array(idx_v)
        # the common case (the UR arm alone) needs no scatter/gather in the hot loops
        self._identity = (self.model.nq == len(idx_q) and np.array_equal(self._idx_q, np.arange(len(idx_q)))
                          and np.array_equal(self._idx_v, np.arange(len(idx_v))))
        self._q_full = pin.neutral(self.model)
        self._chain_order = self._revolute_chain_order()
        self.q_min = self.model.lowerPositionLimit[self._idx_q].copy()
        self.q_max = self.model.upperPositionLimit[self._idx_q].copy()
        self.v_max = self.model.velocityLimit[self._idx_v].copy()
        pose = np.eye(4) if base_pose is None else np.asarray(base_pose, dtype=float)
        if pose.shape != (4, 4) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-9):
            raise ValueError("base_pose must be a 4x4 rigid transform")
        self.base_pose = pose
        self._rb = pose[:3, :3].copy()
        self._has_base = not np.array_equal(pose, np.eye(4))
        for arr in (self.q_min, self.q_max, self.v_max, self.base_pose):
            arr.setflags(write=False)

    def _revolute_chain_order(self) -> np.ndarray | None:
        """Our joints sorted root to frame if all are revolute and on the frame's chain, else None."""
        chain, jid = [], self.model.frames[self.frame_id].parentJoint
        while jid > 0:
            chain.append(jid)
            jid = self.model.parents[jid]
        chain.reverse()
        ids = [self.model.getJointId(name) for name in self.joint_names]
        if any(j not in chain or self.model.joints[j].shortname() not in _REVOLUTE for j in ids):
            return None
        return np.argsort([chain.index(j) for j in ids])

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.joint_names)

    # ------------------------------------------------------------------ frames
    def to_root(self, pose_world: np.ndarray) -> np.ndarray:
        """A world pose (4, 4) expressed in the URDF root frame (base_link)."""
        if not self._has_base:
            return np.asarray(pose_world, dtype=float)
        return np.linalg.inv(self.base_pose) @ np.asarray(pose_world, dtype=float)

    def _full(self, q: np.ndarray) -> np.ndarray:
        if self._identity:
            return np.asarray(q, dtype=float)
        self._q_full[self._idx_q] = q
        return self._q_full

    # ------------------------------------------------------------------ forward
    def fk(self, q: np.ndarray) -> np.ndarray:
        """World pose (4, 4) of the frame at joint positions q (n,) [rad]."""
        pin.framesForwardKinematics(self.model, self.data, self._full(q))
        m = self.data.oMf[self.frame_id].homogeneous
        return self.base_pose @ m if self._has_base else m.copy()

    def fk_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position (3,) [m], rotation (3, 3) and Jacobian (6, n) in one kinematic pass."""
        jac = pin.computeFrameJacobian(self.model, self.data, self._full(q), self.frame_id, _LWA)
        placement = self.data.oMf[self.frame_id]
        if not self._identity:
            jac = jac[:, self._idx_v]
        p, r = placement.translation.copy(), placement.rotation.copy()
        if self._has_base:
            p = self._rb @ p + self.base_pose[:3, 3]
            r = self._rb @ r
            jac = np.vstack([self._rb @ jac[:3], self._rb @ jac[3:]])
        return p, r, jac

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """Geometric Jacobian (6, n), LOCAL_WORLD_ALIGNED, rows (v_origin, omega)."""
        return self.fk_jacobian(q)[2]

    def jacobian_dot_times_qd(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """Drift term dJ/dt qd (6,) [m/s^2, rad/s^2] of the LWA Jacobian.

        It is the frame's classical acceleration (origin acceleration and angular
        acceleration, world axes) at zero joint acceleration, so that the task acceleration
        is ``J qdd + dJ/dt qd``. Pinocchio's spatial acceleration would differ by
        ``omega x v``; the classical one is the time derivative of J qd.
        """
        if self._identity:
            q_full, qd_full = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        else:
            q_full = self._full(q).copy()
            qd_full = np.zeros(self.model.nv)
            qd_full[self._idx_v] = qd
        pin.forwardKinematics(self.model, self.data, q_full, qd_full, np.zeros(self.model.nv))
        pin.updateFramePlacement(self.model, self.data, self.frame_id)
        acc = pin.getFrameClassicalAcceleration(self.model, self.data, self.frame_id, _LWA).vector
        if self._has_base:
            return np.concatenate([self._rb @ acc[:3], self._rb @ acc[3:]])
        return acc.copy()

    def fk_jacobian_batch(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`fk_jacobian` of many configurations q (M, n): (M, 3) [m], (M, 3, 3), (M, 6, n)."""
        q = np.asarray(q, dtype=float).reshape(-1, self.n)
        model, data, fid, frames = self.model, self.data, self.frame_id, self.data.oMf
        jac, pose = np.empty((len(q), 6, model.nv)), np.empty((len(q), 4, 4))
        for k, qk in enumerate(q if self._identity else (self._full(x) for x in q)):
            # one Pinocchio pass per configuration (it places the frame too); the rest is vectorised
            jac[k] = pin.computeFrameJacobian(model, data, qk, fid, _LWA)
            pose[k] = frames[fid].homogeneous
        pos, rot = pose[:, :3, 3], pose[:, :3, :3]
        if not self._identity:
            jac = jac[:, :, self._idx_v]
        if self._has_base:
            pos = pos @ self._rb.T + self.base_pose[:3, 3]
            rot = self._rb @ rot
            jac = np.concatenate([self._rb @ jac[:, :3], self._rb @ jac[:, 3:]], axis=1)
        return pos, rot, jac

    def jacobian_dot_times_qd_batch(self, q: np.ndarray, qd: np.ndarray,
                                    jac: np.ndarray | None = None) -> np.ndarray:
        """:meth:`jacobian_dot_times_qd` of many states (M, n) -> (M, 6); ``jac`` (M, 6, n) at q if known.

        For revolute joints along the frame's chain (any arm of this project) it is computed
        from the Jacobians alone (:func:`serial_drift`), else by Pinocchio state by state.
        """
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        if self._chain_order is None:
            return np.array([self.jacobian_dot_times_qd(a, b) for a, b in zip(q, qd)]).reshape(len(q), 6)
        if jac is None:
            jac = self.fk_jacobian_batch(q)[2]
        order = self._chain_order
        return serial_drift(jac[:, :, order], qd[:, order])

    # ------------------------------------------------------------------ inverse
    def ik(self, target: np.ndarray, q0: np.ndarray, weights: np.ndarray | None = None, *,
           max_iterations: int = 200, tol_pos: float = 1e-6, tol_rot: float = 1e-6,
           max_step: float = 0.5) -> IkResult:
        """Joint positions that put the frame at ``target``, by damped least squares.

        Gauss-Newton on the pose error ``(p_t - p, log3(R_t R^T))`` (world axes, matching the
        LWA Jacobian) with Levenberg-Marquardt damping proportional to the squared error: far
        from the solution (or near a singularity) steps stay short, close to it the step is a
        plain Newton step, so convergence is quadratic. Each step is scaled so that no joint
        moves more than ``max_step`` and the result is clamped to the joint limits.

        Args:
            target: Desired world pose (4, 4).
            q0: Initial guess (n,) [rad].
            weights: (6,) >= 0, ordered (x, y, z, rx, ry, rz) like the Jacobian rows (MATLAB
                orders rotation first; all ones, the seeds' choice, is the same either way).
                A zero weight drops that component from the fit and from the convergence test.
            max_iterations: Steps before giving up.
            tol_pos: Position tolerance [m].
            tol_rot: Rotation tolerance [rad].
            max_step: Largest joint change per step [rad].
        """
        t_world = np.asarray(target, dtype=float)
        if t_world.shape != (4, 4):
            raise ValueError(f"target must be a 4x4 pose; got shape {t_world.shape}")
        w = np.ones(6) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != (6,) or np.any(w < 0) or not np.any(w > 0):
            raise ValueError(f"weights must be (6,) >= 0 with one > 0; got {weights}")
        p_t, r_t = t_world[:3, 3], t_world[:3, :3]
        use_pos, use_rot = bool(np.any(w[:3] > 0)), bool(np.any(w[3:] > 0))
        sqrt_w = np.sqrt(w)
        q = np.clip(np.asarray(q0, dtype=float), self.q_min, self.q_max)
        eye = np.eye(6)
        it = 0
        while True:
            p, r, jac = self.fk_jacobian(q)
            e = np.concatenate([p_t - p, Rotation.from_matrix(r_t @ r.T).as_rotvec()])
            rp, rr = float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))
            done = (not use_pos or rp <= tol_pos) and (not use_rot or rr <= tol_rot)
            if done or it >= max_iterations:
                return IkResult(q, rp, rr, it, done)
            ew = sqrt_w * e
            jw = sqrt_w[:, None] * jac
            # damping ~ |e|^2: large far away (robust near singular guesses), ~0 at the solution
            lam2 = 1e-3 * float(ew @ ew) + 1e-12
            dq = jw.T @ np.linalg.solve(jw @ jw.T + lam2 * eye, ew)
            biggest = float(np.abs(dq).max())
            if biggest > max_step:
                dq *= max_step / biggest
            q = np.clip(q + dq, self.q_min, self.q_max)
            it += 1

    def ik_or_raise(self, target: np.ndarray, q0: np.ndarray, what: str, **kwargs) -> np.ndarray:
        """:meth:`ik`, raising PlanningError naming ``what`` and the residuals on failure."""
        res = self.ik(target, q0, **kwargs)
        if not res.converged:
            raise PlanningError(f"IK failed for {what}: residual {res.residual_pos:.3e} m, "
                                f"{res.residual_rot:.3e} rad after {res.iterations} iterations "
                                f"(frame {self.frame}, q = {np.round(res.q, 4).tolist()})")
        return res.q

    def ik_path(self, targets: np.ndarray, q0: np.ndarray, *, first_iterations: int = 300,
                iterations: int = 20) -> PathIk:
        """IK of a sequence of nearby poses (M, 4, 4), continuing from ``q0`` (n,) [rad].

        Each pose is solved by :meth:`ik` from the previous solutions extrapolated linearly
        (the first from ``q0``), with ``first_iterations`` then ``iterations`` steps; it stops
        at the first pose that does not converge. A continuous path thus stays in the arm
        configuration ``q0`` leads to.
        """
        targets = np.asarray(targets, dtype=float)
        m = len(targets)
        q = np.full((m, self.n), np.nan)
        res_p, res_r = np.full(m, np.nan), np.full(m, np.nan)
        iters = np.zeros(m, dtype=int)
        for k in range(m):
            guess = q0 if k == 0 else q[0] if k == 1 else 2.0 * q[k - 1] - q[k - 2]
            res = self.ik(targets[k], guess, max_iterations=first_iterations if k == 0 else iterations)
            q[k], res_p[k], res_r[k], iters[k] = res.q, res.residual_pos, res.residual_rot, res.iterations
            if not res.converged:
                return PathIk(q, res_p, res_r, iters, k)
        return PathIk(q, res_p, res_r, iters, None)
