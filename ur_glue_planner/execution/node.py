"""The `ur_glue_planner` node: plan the windshield glue job, execute it through FollowJointTrajectory, report.

Works against ur_sim and the real UR driver alike (only their ROS interfaces are used). Parameters:
`job` (YAML path, default config/glue_job.yaml), `out_dir` (default out/<job name>), `namespace` and
`controller_name` (override the job's), `timeout` [s] for the server and joint states, `render` (bool).
Exit codes: 0 success, 2 invalid job, 3 no server or joint states, 4 planning failed, 5 execution failed,
130 cancelled by Ctrl-C / SIGTERM (the active goal is cancelled first).
"""
from __future__ import annotations

import sys
import threading
from pathlib import Path

import rclpy

from ur_glue_planner.errors import ClientError, JobError, PlanningError
from ur_glue_planner.execution.client import URClient
from ur_glue_planner.execution.entry import start_ros
from ur_glue_planner.execution.run import Interrupted, execute
from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.report.glue_report import write_report


def run_job(params: dict, stop: threading.Event, context=None) -> int:
    """Plan, execute and report one job; returns the exit code."""
    try:
        job = load_job(params.get('job') or default_job_path())
    except JobError as exc:
        print(f'ur_glue_planner: invalid job: {exc}', file=sys.stderr)
        return 2
    namespace = params.get('namespace') or job.namespace
    controller = params.get('controller_name') or job.controller_name
    out_dir = Path(params.get('out_dir') or Path('out') / Path(job.source_file or 'glue_job').stem)
    try:
        ur = URClient(namespace=namespace, controller_name=controller, timeout=float(params.get('timeout', 30.0)),
                      context=context, node_name='ur_glue_planner_client')
    except ClientError as exc:
        print(f'ur_glue_planner: {exc}', file=sys.stderr)
        return 3
    try:
        state = ur.joint_state()
        try:
            plan = plan_job(job, state.q)
        except PlanningError as exc:
            print(f'ur_glue_planner: planning failed: {exc}', file=sys.stderr)
            return 4
        s = plan.summary
        print(f'planned: bead {s.bead_length:.3f} m in {s.bead_duration:.2f} s, total {s.total_duration:.2f} s; '
              f'planned speed within 1 % on {100 * s.within_1pct:.1f} % of the bead; planning took '
              f'{1e3 * s.planning_seconds:.0f} ms', flush=True)
        try:
            outcome, run = execute(ur, plan, stop)
        except Interrupted:
            return 130
        summary = write_report(plan, run, outcome.error_code, outcome.error_string, out_dir,
                               render=bool(params.get('render', True)))
        executed = summary.get('executed', {})
        if executed:
            print(f"executed: speed within 1 % on {100 * executed['fraction_within_1pct']:.1f} % of the bead, "
                  f"max tip deviation {executed['max_tip_deviation_mm']:.3f} mm, max joint tracking error "
                  f"{1e3 * executed['max_joint_tracking_error_rad']:.3f} mrad")
        print(f'report: {out_dir.resolve()}', flush=True)
        return 0 if outcome.succeeded else 5
    finally:
        ur.close()


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_glue_planner` (and `ros2 run ur_sim_driver ur_glue_planner`)."""
    params, stop = start_ros('ur_glue_planner', argv)
    try:
        return run_job(params, stop, context=rclpy.get_default_context())
    except KeyboardInterrupt:
        return 130
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    sys.exit(main())
