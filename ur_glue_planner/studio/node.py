"""The `ur_glue_studio` executable: the glue studio in the browser, or a live viewer without a job.

Parameters: `job` (YAML path; none: live viewer only), `host` (default 127.0.0.1), `port` (8080), `namespace` and
`controller_name` (override the job's, for Run and the live topics), `save_path` (default of Save).
`ros2 run ur_sim_driver ur_glue_studio --ros-args -p job:=config/glue_job.yaml -p port:=8080`; stops on
Ctrl-C / SIGTERM (a running goal is cancelled first). Exit codes: 0, 2 invalid parameter or job file.
"""
from __future__ import annotations

import sys

import rclpy

from ur_glue_planner.errors import JobError
from ur_glue_planner.execution.entry import start_ros
from ur_glue_planner.studio.job_file import read_job
from ur_glue_planner.studio.ros_link import LiveRobot

ROS_PARAMETERS = {'use_sim_time', 'start_type_description_service'}  # every rclpy node has these
DEFAULTS = {'job': '', 'host': '127.0.0.1', 'port': 8080, 'namespace': '', 'controller_name': '',
            'save_path': 'out/studio/glue_job.yaml'}


def parse_params(raw: dict) -> dict:
    """The studio's parameters with defaults; raises ValueError naming a bad one."""
    unknown = sorted(set(raw) - set(DEFAULTS) - ROS_PARAMETERS)
    if unknown:
        raise ValueError(f"parameter {unknown[0]!r} is unknown; known: {', '.join(DEFAULTS)}")
    params = {**DEFAULTS, **raw}
    port = params['port']
    if not isinstance(port, int) or isinstance(port, bool) or not 1 <= port <= 65535:
        raise ValueError(f'port: {port!r} is not an integer in [1, 65535]')
    for key in ('job', 'host', 'namespace', 'controller_name', 'save_path'):
        if not isinstance(params[key], str):
            raise ValueError(f'{key}: {params[key]!r} is not a string')
    return params


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_glue_studio` (and `ros2 run ur_sim_driver ur_glue_studio`)."""
    raw, stop = start_ros('ur_glue_studio_params', argv)
    try:
        params = parse_params(raw)
        job_path = params['job'] or None
        namespace = params['namespace']
        if job_path is not None:
            namespace = namespace or read_job(job_path).job.namespace
    except (ValueError, JobError) as exc:
        print(f'ur_glue_studio: {exc}', file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    from ur_glue_planner.studio.app import Studio  # viser and the scene load only when the parameters are good
    live = LiveRobot(namespace, context=rclpy.get_default_context())
    studio = Studio(job_path, params['host'], params['port'], live=live, namespace=params['namespace'],
                    controller_name=params['controller_name'], save_path=params['save_path'])
    what = f'job {job_path}' if job_path else 'live viewer (no job)'
    print(f"ur_glue_studio: {what} on http://{params['host']}:{studio.server.get_port()}", flush=True)
    try:
        while not stop.wait(0.5):  # a timed wait lets the signal handler run promptly
            pass
    except KeyboardInterrupt:
        pass
    finally:
        studio.close()
        live.close()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
