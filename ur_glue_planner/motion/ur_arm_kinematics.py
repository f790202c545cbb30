"""Kinematics of a UR arm's tool frame: Pinocchio, with the closed-form IK for seeds and branches.

:class:`UrKinematics` is a :class:`~ur_glue_planner.motion.kinematics.Kinematics` whose path IK
(:meth:`UrKinematics.ik_path`) solves every pose at once in closed form
(:mod:`~ur_sim_driver.description.analytic_ik`), keeps the branch the first pose's Newton solution
is in, and then checks each sample with Pinocchio's forward kinematics of the URDF: a sample
more than the IK tolerance off is refined by Newton steps (:meth:`Kinematics.ik`). Where the
branch ends (out of reach) or leaves the joint limits, per-sample Newton takes over, so
failures are found and reported exactly as without the closed form.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ur_glue_planner.motion.kinematics import Kinematics, PathIk, pose_errors
from ur_sim_driver.description.analytic_ik import UrAnalyticIK, follow_branch, nearest_branch
from ur_sim_driver.description.params import DH, URParams, joint_names, load_ur_params
from ur_sim_driver.description.tool import ToolDef, get_tool
from ur_sim_driver.description.urdf import build_urdf

# [rad] the Newton solution of the first pose (within 1e-6 m / 1e-6 rad) lies this close to its
# closed-form twin; anything farther is a different branch (or a singular pose)
_SAME_BRANCH = 1e-3
# configurations at which the closed form is compared with the URDF's forward kinematics
_CHECK_Q = np.array([[0.0, -1.5, 1.2, -0.7, 1.4, 0.3], [2.1, -0.4, -2.2, 1.9, -0.8, -2.7],
                     [-1.3, -2.6, 0.5, 2.8, 2.2, 1.1]])


class NotOnFlangeError(ValueError):
    """The frame is not rigidly fixed to the flange: the closed form does not apply to it."""


class UrKinematics(Kinematics):
    """:class:`Kinematics` of a frame fixed to a UR arm's ``tool0`` (tool0 itself, a tool tip, ...).

    Args:
        urdf, joint_names, frame, base_pose: As for :class:`Kinematics`.
        dh: The arm's DH lengths [m], those the URDF was built from.
        tool0: Name of the flange frame (DH frame 6) in the URDF.

    Raises:
        NotOnFlangeError: ``frame`` is not rigidly fixed to ``tool0``.
        ValueError: An unknown name, or the URDF's forward kinematics differs from the closed
            form's (more than 1e-9).
    """

    def __init__(self, urdf: str, joint_names: Sequence[str], frame: str, dh: DH,
                 base_pose: np.ndarray | None = None, tool0: str = "tool0") -> None:
        super().__init__(urdf, joint_names, frame, base_pose)
        if not self.model.existFrame(tool0):
            raise ValueError(f"frame {tool0!r} is not in the model")
        flange = self.model.getFrameId(tool0)
        if self.model.frames[flange].parentJoint != self.model.frames[self.frame_id].parentJoint:
            raise NotOnFlangeError(f"frame {frame!r} is not fixed to {tool0!r}: no closed-form IK for it")
        pin.framesForwardKinematics(self.model, self.data, pin.neutral(self.model))
        offset = (self.data.oMf[flange].inverse() * self.data.oMf[self.frame_id]).homogeneous
        self.analytic = UrAnalyticIK(dh, offset, self.base_pose)
        error = float(np.abs(self.analytic.fk(_CHECK_Q) - np.array([self.fk(q) for q in _CHECK_Q])).max())
        if error > 1e-9:
            raise ValueError(f"the URDF's forward kinematics differs from the closed form of DH {dh} "
                             f"by {error:.2e}: not a plain UR arm")

    def ik_solutions(self, target: np.ndarray) -> np.ndarray:
        """All closed-form solutions (8, n) [rad] of a world pose (4, 4); NaN rows are unreachable."""
        return self.analytic.solve(np.asarray(target, dtype=float))

    def ik_path(self, targets: np.ndarray, q0: np.ndarray, *, first_iterations: int = 300,
                iterations: int = 20) -> PathIk:
        """:meth:`Kinematics.ik_path`, in closed form where the branch of the first pose reaches.

        The first pose is solved by Newton from ``q0`` (so the branch is the one IK from q0
        lands in), the others are that branch's closed-form solutions made continuous, each
        checked with Pinocchio and refined by Newton if it is off by more than 1e-6 m / rad.
        """
        targets = np.asarray(targets, dtype=float)
        m = len(targets)
        first = self.ik(targets[0], q0, max_iterations=first_iterations)
        branch, distance = nearest_branch(self.analytic.solve(targets[0]), first.q)
        if not first.converged or distance > _SAME_BRANCH:  # unreachable, or a singular start
            return super().ik_path(targets, q0, first_iterations=first_iterations, iterations=iterations)
        q = follow_branch(self.analytic.solve(targets, branch), first.q)
        q[0] = first.q
        # the closed form ends where the branch leaves the workspace or the joint limits
        out = np.flatnonzero(~np.all((q >= self.q_min) & (q <= self.q_max), axis=1))  # NaN fails too
        end = int(out[0]) if out.size else m
        iters = np.zeros(m, dtype=int)
        iters[0] = first.iterations
        pos, rot, jac = self.fk_jacobian_batch(q[:end])
        res_p, res_r = pose_errors(targets[:end], pos, rot)
        for k in np.flatnonzero((res_p > 1e-6) | (res_r > 1e-6)):
            res = self.ik(targets[k], q[k], max_iterations=iterations)
            if not res.converged:
                end = int(k)
                break
            q[k], iters[k] = res.q, res.iterations
            pos[k], rot[k], jac[k] = self.fk_jacobian(res.q)
            res_p[k], res_r[k] = res.residual_pos, res.residual_rot
        if end == m:
            return PathIk(q, res_p, res_r, iters, None, pos, rot, jac)
        # Newton from the last closed-form sample on: it reports the failure (or finds a way on)
        tail = super().ik_path(targets[end:], q[end - 1] if end else q0,
                               first_iterations=iterations if end else first_iterations, iterations=iterations)
        return PathIk(np.vstack([q[:end], tail.q]), np.concatenate([res_p[:end], tail.residual_pos]),
                      np.concatenate([res_r[:end], tail.residual_rot]),
                      np.concatenate([iters[:end], tail.iterations]),
                      None if tail.failed is None else end + tail.failed)


def ur_kinematics(robot: URParams | str, tool: ToolDef | str | None = "dispenser", frame: str | None = None,
                  base_pose: np.ndarray | None = None, tf_prefix: str = "") -> Kinematics:
    """Kinematics of a UR arm from ``ur_sim_driver``'s description (no simulator import).

    A frame fixed to the flange (tool0, a tool tip, ...) gets a :class:`UrKinematics`, whose
    path IK uses the closed-form UR solution; any other frame a plain :class:`Kinematics`.

    Args:
        robot: The arm's parameters, or its type's name (one of UR_TYPES, e.g. 'ur5e'), loaded here.
        tool: Tool on tool0, or its name ('dispenser' or None/'none').
        frame: Frame to compute; default: the tool tip, or 'tool0' without a tool.
        base_pose: World pose (4, 4) of base_link; identity (robot at the world origin) if None.
        tf_prefix: Prefix of every frame and joint name.
    """
    params = load_ur_params(robot) if isinstance(robot, str) else robot
    tool_def = get_tool(tool) if tool is None or isinstance(tool, str) else tool
    if frame is None:
        frame = tool_def.tip_name if tool_def is not None else "tool0"
    urdf = _ur_urdf(params, tool_def, tf_prefix)
    try:
        return UrKinematics(urdf, joint_names(tf_prefix), tf_prefix + frame, params.dh, base_pose, tf_prefix + "tool0")
    except NotOnFlangeError:
        return Kinematics(urdf, joint_names(tf_prefix), tf_prefix + frame, base_pose=base_pose)


_URDFS: dict[tuple[str, ToolDef | None, str], str] = {}


def _ur_urdf(params: URParams, tool: ToolDef | None, tf_prefix: str) -> str:
    """The URDF string of an arm with a tool (built once per process and type: it is pure and immutable)."""
    key = (params.name, tool, tf_prefix)
    if key not in _URDFS:
        _URDFS[key] = build_urdf(params, tf_prefix=tf_prefix, tool=tool)
    return _URDFS[key]
