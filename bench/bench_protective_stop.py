"""Protective stop benchmark: the dispenser tip driven into the windshield at 0.15 m/s (issue 10, point 7).

ur_sim runs in this process without its loop thread: the benchmark steps it cycle by cycle (as the loop does)
and reads, after every cycle, the tip's position along the tool axis and the contacts. Reported: the control
cycle the stop came in after the first contact (the safety system acts on a mean of the contact force,
``safety.py``), the tip's travel from the first contact and from the stop to
standstill, and the deepest penetration of any contact.
"""
from __future__ import annotations

import dataclasses
import platform

import numpy as np
from rclpy.parameter import Parameter

from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.approach import JointSegment, joint_move
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.touch import touch_move
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.scene.waypoints import tool_axis
from ur_sim_driver.motion.trajectory_types import TrajectoryPoints
from ur_sim_driver.robot.robot_state import PROTECTIVE_STOP
from ur_sim_driver.ros.node import UrSimNode

SPEED = 0.15  # [m/s] tip speed at the glass


def _points(node: UrSimNode, seg: JointSegment) -> TrajectoryPoints:
    n = len(seg.times)
    return TrajectoryPoints(node.joints, seg.times, seg.q, seg.qd, seg.qdd, np.ones(n, bool), np.ones(n, bool))


def _run(node: UrSimNode, seg: JointSegment, seconds: float, each=None) -> None:
    with node.host.lock:
        s = node.sim.state()
        node.jtc.start(_points(node, seg), s.t, s.q, s.qd)
    for _ in range(round(seconds * node.sim.control_rate)):
        node.step_once()
        if each is not None:
            each()


def measure(ctx, ur_type: str | None = None) -> dict:
    """The stop of the job's robot (`ur_type` None: the job's UR5 at 125 Hz), or of another type."""
    job = load_job(default_job_path())
    if ur_type is not None:
        job = dataclasses.replace(job, ur_type=ur_type)
    node = UrSimNode(context=ctx, start=False, parameter_overrides=[
        Parameter('ur_type', value=job.ur_type), Parameter('tool', value='dispenser'),
        Parameter('scene', value='windshield'), Parameter('real_time_factor', value=0.0)])
    try:
        kin = ur_kinematics(job.ur_type, job.tool)
        plan = plan_job(job, node.sim.state().q)
        axis = tool_axis(job.tool)
        surface = kin.fk(plan.bead.q[0])
        u = surface[:3, :3] @ (axis / np.linalg.norm(axis))
        seg = touch_move(kin, plan.bead.q[0], axis, height=0.02, depth=0.02, speed=SPEED, dt=job.sample_time)
        p = node.sim.params
        _run(node, joint_move(node.sim.state().q, seg.q[0], p.v_max, p.a_max, job.sample_time, min_duration=2.0),
             2.5)
        log = []

        def sample():
            t = node.sim.time
            tip = kin.fk(node.sim.state().q)[:3, 3]
            contacts = node.sim.physics.contacts()
            log.append((t, float((tip - surface[:3, 3]) @ u), max((c.depth for c in contacts), default=0.0),
                        max((c.force for c in contacts), default=0.0), node.robot.safety_mode == PROTECTIVE_STOP))

        _run(node, seg, seg.times[-1] + 1.0, sample)
        t, along, depth, force, stopped = (np.array(c) for c in zip(*log))
        first = int(np.argmax(force > 0.0)) if (force > 0.0).any() else None
        stop = int(np.argmax(stopped)) if stopped.any() else None
        dt = node.sim.control_dt
        return {
            'ur_type': job.ur_type, 'control_rate_hz': node.sim.control_rate, 'tip_speed_m_s': SPEED,
            'threshold_n': node.cfg.protective_stop_force, 'window_s': node.cfg.protective_stop_window,
            'stopped': stop is not None,
            'cycles_from_first_contact_to_stop': None if first is None or stop is None else stop - first,
            'force_at_stop_n': None if stop is None else float(force[stop]),
            'tip_beyond_surface_at_first_contact_mm': None if first is None else 1e3 * float(along[first]),
            'tip_travel_after_first_contact_mm': None if first is None else 1e3 * float(along.max() - along[first]),
            'stop_distance_mm': None if stop is None else 1e3 * float(along.max() - along[stop]),
            'deepest_penetration_mm': 1e3 * float(depth.max()),
            'max_force_n': float(force.max()),
            'time_to_standstill_ms': None if stop is None else 1e3 * float(t[int(np.argmax(along))] - t[stop]),
            'period_ms': 1e3 * dt,
        }
    finally:
        node.shutdown()
        node.destroy_node()


def run() -> dict:
    import rclpy
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    try:
        result = measure(ctx)
        result['ur5e'] = measure(ctx, 'ur5e')  # 500 Hz: the force mean spans 5 cycles
    finally:
        rclpy.try_shutdown(context=ctx)
    result['machine'] = {'cpus': __import__('os').cpu_count(), 'python': platform.python_version(),
                         'processor': platform.processor() or platform.machine()}
    return result


if __name__ == '__main__':
    import json
    print(json.dumps(run(), indent=2))
