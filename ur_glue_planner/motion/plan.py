"""``plan_job``: the whole glue job as inspectable stages, pure (no ROS, no simulator).

Stages: waypoints -> path (corners rounded) -> nominal time law -> IK branch -> bead joint
trajectory (re-timed where the joints need it) -> joint move to the approach pose -> descent
along the tool axis -> bead -> lift-off along the tool axis.

The bead's IK branch is chosen independently of the robot's current state (from the job's
``ik_seed_deg`` or else the best branch nearest to ``home``), so a job always lays its bead
the same way; only the first joint move depends on where the robot is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ur_glue_planner.errors import PlanningError
from ur_glue_planner.job import GlueJob
from ur_glue_planner.motion.approach import JointSegment, joint_move, tool_axis_move
from ur_glue_planner.motion.clearance import Clearance
from ur_glue_planner.motion.dispense import DispenseSchedule, run_up_length, schedule_dispenser
from ur_glue_planner.motion.ik_branch import Branch, choose_branch
from ur_glue_planner.motion.joint_trajectory import JointPlan, build_joint_plan
from ur_glue_planner.motion.kinematics import Kinematics
from ur_glue_planner.motion.reach import reach_refusal
from ur_glue_planner.motion.seed1 import seed1_bead
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.path.glue_path import GluePath, build_glue_path
from ur_glue_planner.path.run_up import RunUpPath
from ur_glue_planner.path.surface_path import SurfacePath
from ur_glue_planner.path.timing import PathTiming, time_path
from ur_glue_planner.scene.registration import Registration
from ur_glue_planner.scene.waypoints import job_waypoints, tool_axis, windshield_model
from ur_glue_planner.scene.windshield import WindshieldModel
from ur_sim_driver.description.params import URParams, load_ur_params
from ur_sim_driver.description.tool import ToolDef, get_tool


@dataclass(frozen=True)
class PlanSummary:
    """Headline numbers of a plan.

    Attributes:
        bead_length: [m]. bead_duration: [s]. total_duration: all segments [s].
        speed_mean, speed_min, speed_max: planned tip speed [m/s] over the bead's cruise (from
            the end of the start ramp to the start of the stop ramp, slowdowns included).
        within_1pct: Fraction of the bead length where the planned speed is within 1 % of
            the commanded one.
        max_velocity_usage: Largest |qd| / v_max of any joint in any segment.
        max_acceleration: Largest |qdd| [rad/s^2] in any segment (limit: ``a_max``).
        a_max: The joint acceleration limit used [rad/s^2].
        ik_residual_pos: [m]; ik_residual_rot: [rad]; largest over the bead samples.
        ik_seconds: Wall time [s] of the final bead IK pass; bead_samples: its sample count.
        planning_seconds: Wall time [s] of plan_job.
        slowdowns: Number of re-timed stretches.
    """

    bead_length: float
    bead_duration: float
    total_duration: float
    speed_mean: float
    speed_min: float
    speed_max: float
    within_1pct: float
    max_velocity_usage: float
    max_acceleration: float
    a_max: float
    ik_residual_pos: float
    ik_residual_rot: float
    ik_seconds: float
    bead_samples: int
    planning_seconds: float
    slowdowns: int


@dataclass(frozen=True, eq=False)
class GluePlan:
    """Every stage of a planned glue job.

    Attributes:
        job: The job.
        kinematics: Tip kinematics used.
        waypoints: (K, 3) [m]; orientations: (K, 3, 3); world frame.
        path: Bead geometry (the intended line). nominal_timing: the motion's time law before any slowdown.
        motion_path: What the tip walks during the bead segment: ``path`` (laid onto the glass by a
            SurfacePath with ``path.follow_surface``), with a flying start inside a RunUpPath; bead.s is its arc
            length, and ``run_up`` [m] is where the bead itself starts on it.
        branch: The IK branch of the bead start (None if the job gave ``ik_seed_deg``);
            branches: all examined.
        bead: The bead in joint space (its ``timing`` is the final time law).
        approach: Joint move from the current state to the descent start (or the bead start).
        descent, retreat: Straight tool-axis moves onto and off the bead, or None.
        summary: Headline numbers.
        dispense: When the glue gun is switched (bead segment time).
        line: The intended bead centre line (P, 3) [m], about 1 mm apart: the rounded path on the glass (the
            tip stands off above it along the nozzle axis), or for seed 1 the waypoint polyline it walks.
        robot, tool: The arm's parameters and its tool, resolved once from the job's names.
        method: 'constant_speed' (ours) or 'seed1'.
        surface: The glass the bead was laid on: the job's nominal glass, or the measured part.
        part: The measurement the path was moved by (None: planned on the nominal glass).
    """

    job: GlueJob
    kinematics: Kinematics
    waypoints: np.ndarray
    orientations: np.ndarray
    path: GluePath
    nominal_timing: PathTiming
    branch: Branch | None
    branches: tuple[Branch, ...]
    bead: JointPlan
    approach: JointSegment
    descent: JointSegment | None
    retreat: JointSegment | None
    summary: PlanSummary
    dispense: DispenseSchedule
    line: np.ndarray
    motion_path: GluePath | RunUpPath
    robot: URParams
    tool: ToolDef | None
    run_up: float = 0.0
    method: str = "constant_speed"
    surface: WindshieldModel | None = None
    part: Registration | None = None

    def segments(self) -> tuple[JointSegment, ...]:
        """The motion in execution order, each starting at its own time 0."""
        bead = JointSegment("bead", self.bead.times, self.bead.q, self.bead.qd, self.bead.qdd)
        return tuple(s for s in (self.approach, self.descent, bead, self.retreat) if s is not None)


def speed_within(s: np.ndarray, speed: np.ndarray, target: float, tolerance: float = 0.01) -> float:
    """Fraction of the arc length s (M,) [m] where ``speed`` (M,) is within ``tolerance`` of target.

    An interval between two samples counts if the speed at both ends is within.
    """
    ok = np.abs(speed - target) <= tolerance * target
    ds = np.diff(s)
    return float(ds[ok[1:] & ok[:-1]].sum() / ds.sum())


def densify(polyline: np.ndarray, step: float = 0.001) -> np.ndarray:
    """Points (P, 3) along a polyline (K, 3) [m] at most ``step`` [m] apart, corners kept."""
    out = [polyline[:1]]
    for a, b in zip(polyline[:-1], polyline[1:]):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / step)))
        out.append(a + (np.arange(1, n + 1) / n)[:, None] * (b - a))
    return np.vstack(out)


def _check_limits(seg: JointSegment, kin: Kinematics, a_max: float) -> None:
    for what, values, limit in (("velocity", seg.qd, kin.v_max), ("acceleration", seg.qdd, a_max)):
        ratio = np.abs(values) / limit
        if ratio.max() > 1.0 + 1e-6:
            k, j = np.unravel_index(np.argmax(ratio), ratio.shape)
            raise PlanningError(f"{seg.name}: joint {kin.joint_names[j]} {what} {values[k, j]:.3f} exceeds "
                                f"{np.broadcast_to(limit, ratio.shape[1:])[j]:.3f} at t = {seg.times[k]:.2f} s")
    if np.any(seg.q < kin.q_min - 1e-9) or np.any(seg.q > kin.q_max + 1e-9):
        raise PlanningError(f"{seg.name}: leaves the joint position limits")


def plan_job(job: GlueJob, q_current: np.ndarray, qd_current: np.ndarray | None = None,
             qdd_current: np.ndarray | None = None, part: Registration | None = None) -> GluePlan:
    """Plan ``job`` for a robot now at joint state (q, qd, qdd) (6,) [rad, rad/s, rad/s^2]; with ``part`` (the
    part as measured), the bead's waypoints move with it onto the measured glass and the path follows that glass.

    Raises:
        PlanningError: Any stage fails (the message names the stage, sample and joint).
    """
    t0 = time.perf_counter()
    params, tool = load_ur_params(job.ur_type), get_tool(job.tool)  # the job's names, resolved once
    kin = ur_kinematics(params, tool)
    axis = tool_axis(tool)
    points, rots = job_waypoints(job, axis, part)
    surface = windshield_model(job.windshield) if part is None else part.model
    refusal = reach_refusal(points, rots, params, tool)
    if refusal is not None:
        raise PlanningError(refusal)
    clearance = Clearance(params, tool)
    path = build_glue_path(points, rots, max_deviation=job.path.corner_max_deviation, closed=job.path.closed)
    seed1 = job.method == "seed1"
    bead_path = path
    if job.path.follow_surface and not seed1:
        bead_path = SurfacePath(path, surface, job.standoff,
                                tuple(float(x) for x in axis))
    motion_path, run_up = bead_path, 0.0
    if path.closed and job.dispenser.flying_start and not seed1:
        run_up = run_up_length(job.dispenser, job.tcp_speed, job.ramp_time)
        motion_path = RunUpPath(bead_path, run_up, run_up)
    nominal = time_path(motion_path.length, job.tcp_speed, job.sample_time, job.ramp_time)

    branch, branches = None, ()
    if job.ik_seed is not None:
        q_guess = np.array(job.ik_seed)
    else:
        branch, branches = choose_branch(motion_path, kin, np.array(job.home), job.tcp_speed, clearance=clearance)
        q_guess = branch.q
    if seed1:
        bead, corners = seed1_bead(kin, points, rots, q_guess, job.tcp_speed, job.sample_time, job.path.closed)
        line = densify(corners)
        nominal = bead.timing
    else:
        bead = build_joint_plan(motion_path, nominal, kin, q_guess, a_max=params.a_max)
        ss = np.linspace(0.0, path.length, max(2, int(np.ceil(path.length / 0.001)) + 1))
        # the glass under the path (the tip may stand off along the tilted axis, the bead does not)
        line = surface.project(path.sample(ss)[0])[1] \
            if job.path.follow_surface else path.sample(ss)[0]
    dispense = schedule_dispenser(job.dispenser, bead.times, bead.s, bead.tcp_speed, run_up,
                                  bead.s[-1] if seed1 else run_up + path.length, job.tcp_speed)

    start_pose, end_pose = kin.fk(bead.q[0]), kin.fk(bead.q[-1])
    descent = retreat = None
    goal = bead.q[0]
    if job.approach_distance > 0.0:
        descent = tool_axis_move(kin, bead.q[0], start_pose, axis, job.approach_distance, job.approach_speed,
                                 job.sample_time, toward_anchor=True, name="descent")
        goal = descent.q[0]
    if job.retreat_distance > 0.0:
        retreat = tool_axis_move(kin, bead.q[-1], end_pose, axis, job.retreat_distance, job.approach_speed,
                                 job.sample_time, toward_anchor=False, name="retreat")
    approach = joint_move(np.asarray(q_current, dtype=float), goal, kin.v_max, params.a_max, job.sample_time,
                          qd0=qd_current, qdd0=qdd_current, velocity_scale=job.approach_velocity_scale,
                          min_duration=job.approach_min_duration, q_min=kin.q_min, q_max=kin.q_max)
    segments = [s for s in (approach, descent, retreat) if s is not None]
    for seg in segments:
        _check_limits(seg, kin, params.a_max)
    for name, times, q in [(s.name, s.times, s.q) for s in segments] + [("bead", bead.times, bead.q)]:
        touch = clearance.first_touch(q)
        if touch is not None:
            raise PlanningError(f"{name}: {touch.describe()} at t = {times[touch.index]:.2f} s (q = "
                                f"{np.round(q[touch.index], 3).tolist()} rad); the arm would stop on contact")

    timing = bead.timing
    cruise = (bead.times >= timing.piece_t[1]) & (bead.times <= timing.piece_t[-2])
    if not np.any(cruise):
        cruise = np.ones(len(bead.times), dtype=bool)
    all_qd = np.vstack([bead.qd] + [s.qd for s in segments])
    all_qdd = np.vstack([bead.qdd] + [s.qdd for s in segments])
    summary = PlanSummary(
        bead_length=path.length, bead_duration=float(bead.times[-1]),
        total_duration=float(bead.times[-1] + sum(s.duration for s in segments)),
        speed_mean=float(bead.tcp_speed[cruise].mean()), speed_min=float(bead.tcp_speed[cruise].min()),
        speed_max=float(bead.tcp_speed[cruise].max()),
        within_1pct=speed_within(bead.s, bead.tcp_speed, job.tcp_speed),
        max_velocity_usage=float((np.abs(all_qd) / kin.v_max).max()),
        max_acceleration=float(np.abs(all_qdd).max()), a_max=float(params.a_max),
        ik_residual_pos=float(bead.ik_residual_pos.max()), ik_residual_rot=float(bead.ik_residual_rot.max()),
        ik_seconds=bead.ik_seconds, bead_samples=len(bead.times),
        planning_seconds=time.perf_counter() - t0, slowdowns=len(bead.slowdowns))
    return GluePlan(job=job, kinematics=kin, waypoints=points, orientations=rots, path=path, nominal_timing=nominal,
                    branch=branch, branches=branches, bead=bead, approach=approach, descent=descent,
                    retreat=retreat, summary=summary, dispense=dispense, line=line, motion_path=motion_path,
                    robot=params, tool=tool, run_up=run_up, method=job.method, surface=surface, part=part)


