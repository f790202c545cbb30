"""The `ur_glue_planner` node: plan the windshield glue job, execute it through FollowJointTrajectory, report.

Works against ur_sim and the real UR driver alike (only their ROS interfaces are used). Parameters:
`job` (YAML path, default config/glue_job.yaml), `out_dir` (default out/<job name>), `namespace` and
`controller_name` (override the job's), `timeout` [s] for the server and joint states, `render` (bool),
`method` (constant_speed or seed1, overrides the job's), `compare` (bool: run the other method after it on the
same job and put both beads side by side), `video` (bool: out_dir/run.mp4), `video_fps` (frames per second of
robot time, 1 to 60, default 30), `dispense` (bool: switch the glue
gun on the job's output), `measure_part` (bool, default true: read the cell's part scanners on ur_sim/part_scan,
fit the part and move the bead onto it; without scanners the job runs on the nominal glass), `pace_topic` (a
ur_sim started with the same `pace_topic` runs in step with this client, so the gun's switches land where planned
however loaded the machine is; `make parts` runs so). The report:
out_dir/index.html gathers the video, the bead targets and every figure; the run itself is recorded in
out_dir/bag/ (rosbag2, MCAP: execution/bag_recorder.py).
Exit codes: 0 success, 2 invalid job, 3 no server or joint states, 4 planning failed, 5 execution failed,
6 the part was refused (outside what the cell corrects; nothing dispensed), 130 cancelled by Ctrl-C / SIGTERM (the
active goal is cancelled first).
"""
from __future__ import annotations

import json
import sys
import threading
from dataclasses import replace
from pathlib import Path

import rclpy

from ur_glue_planner.errors import ClientError, JobError, PlanningError
from ur_glue_planner.execution.bead_listener import BeadListener
from ur_glue_planner.execution.client import URClient
from ur_glue_planner.execution.dispenser_io import SET_IO, dispenser_for
from ur_glue_planner.execution.entry import start_ros
from ur_glue_planner.execution.part_measure import SCAN_TOPIC, measure_part, read_scan
from ur_glue_planner.execution.part_measure import describe as describe_part
from ur_glue_planner.execution.run import Interrupted, execute
from ur_glue_planner.job import METHODS, _choice, default_job_path, load_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.report.bead_report import LABELS, analyse_bead, write_bead_figure
from ur_glue_planner.report.glue_report import scene_meshes, write_report
from ur_glue_planner.report.html_page import write_index
from ur_glue_planner.report.video import render_video
from ur_glue_planner.scene.registration import Registration
from ur_glue_planner.scene.waypoints import windshield_model


def _bead_line(label: str, bead: dict | None) -> str:
    if not bead:
        return f'{label}: no bead collected'
    if 'width_mm' not in bead:
        return f"{label}: no bead on the line ({bead.get('deposit_points', 0)} deposit points)"
    w, lat = bead['width_mm'], bead['lateral_deviation_mm']
    closure = bead.get('closure', {}).get('overlap_mm')
    return (f"{label}: width {w['mean']:.2f} mm (nominal {bead['nominal_width_mm']:.2f}, min {w['min']:.2f}, "
            f"max {w['max']:.2f}), within +-5 % on {100 * bead['width_within_band_fraction']:.1f} % of the "
            f"length, gaps {bead['gap_length_mm']:.1f} mm, blobs {len(bead['blobs'])}, lateral max "
            f"{lat['max']:.3f} mm" + (f', closure overlap {closure:+.1f} mm' if closure is not None else ''))


def _measured_part(ur: URClient, namespace: str, job) -> tuple[Registration | None, str | None]:
    """The part as the cell's scanners see it (None: no scanners), and why it is refused (None: accepted)."""
    profiles = read_scan(ur.node, namespace)
    if profiles is None:
        print(f'no part scan on {SCAN_TOPIC}: the bead is planned on the nominal glass', flush=True)
        return None, None
    found, reason = measure_part(profiles, windshield_model(job.windshield))
    if found is not None:
        print(describe_part(found), flush=True)
    return found, reason


def run_job(params: dict, stop: threading.Event, context=None) -> int:
    """Plan, execute and report one job (and, with `compare`, the baseline method after it); returns the exit
    code."""
    try:
        job = load_job(params.get('job') or default_job_path())
        if params.get('method'):
            job = replace(job, method=_choice(params['method'], 'method', METHODS))
        video_fps = _video_fps(params.get('video_fps', VIDEO_FPS))
    except JobError as exc:
        print(f'ur_glue_planner: invalid job: {exc}', file=sys.stderr)
        return 2
    namespace = params.get('namespace') or job.namespace
    controller = params.get('controller_name') or job.controller_name
    out_dir = Path(params.get('out_dir') or Path('out') / Path(job.source_file or 'glue_job').stem)
    methods = [job.method]
    if params.get('compare', False):
        methods.append('seed1' if job.method != 'seed1' else 'constant_speed')
    try:
        ur = URClient(namespace=namespace, controller_name=controller, timeout=float(params.get('timeout', 30.0)),
                      context=context, node_name='ur_glue_planner_client')
    except ClientError as exc:
        print(f'ur_glue_planner: {exc}', file=sys.stderr)
        return 3
    try:
        prefix = '/' + namespace.strip('/') if namespace.strip('/') else ''
        pace_topic = params.get('pace_topic') or None
        gun = dispenser_for(ur.node, prefix, controller, pace_topic) if params.get('dispense', True) else None
        if gun is not None and pace_topic is not None:
            gun.follow_joint_states(ur.on_joint_state)
        if gun is not None and not gun.available(timeout=5.0):
            print(f'ur_glue_planner: no {SET_IO} service: running without switching the dispenser', flush=True)
            gun = None
        bead = BeadListener(ur.node, namespace)
        if not bead.available(timeout=2.0 if gun is not None else 0.1):
            bead = None  # a real driver: no simulated bead
        part = None
        if params.get('measure_part', True):
            part, reason = _measured_part(ur, namespace, job)
            if reason is not None:
                print(f'ur_glue_planner: part refused, nothing dispensed: {reason}', file=sys.stderr)
                return 6
        results = []
        for i, method in enumerate(methods):
            plan_for = replace(job, method=method)
            if method == 'seed1':
                # Seed 1 sends its trajectory with MATLAB's followTrajectory, without path tolerances; its
                # unblended corners ask for up to ~160 rad/s^2, which no arm follows within the job's 0.1 rad,
                # so the baseline runs as the seed does: path tolerance unchecked (-1), goal tolerance kept.
                plan_for = replace(plan_for, tolerances=replace(job.tolerances, path_position=(-1.0,) * 6))
            try:
                plan = plan_job(plan_for, ur.joint_state().q, part=part)
            except PlanningError as exc:
                print(f'ur_glue_planner: planning ({method}) failed: {exc}', file=sys.stderr)
                return 4
            s, d = plan.summary, plan.dispense
            print(f'planned ({method}): bead {s.bead_length:.3f} m in {s.bead_duration:.2f} s, total '
                  f'{s.total_duration:.2f} s; planned speed within 1 % on {100 * s.within_1pct:.1f} % of the bead; '
                  f'planning took {1e3 * s.planning_seconds:.0f} ms', flush=True)
            print(f'dispenser: output {d.pin} on at {d.t_on:.3f} s (lead {d.lead:.3f} s before the tip reaches '
                  f'the bead start at {d.t_arrive:.3f} s), off at {d.t_off:.3f} s (lag {d.lag:.3f} s before it '
                  f'reaches the end at {d.t_leave:.3f} s)', flush=True)
            sub = out_dir if i == 0 else out_dir / method
            try:
                outcome, run = execute(ur, plan, stop, gun=gun, bead=bead, bag_dir=sub / 'bag')
            except Interrupted:
                return 130
            except ClientError as exc:  # the robot stopped answering (a service or a goal response timed out)
                print(f'ur_glue_planner: execution ({method}) failed: {exc}', file=sys.stderr)
                return 3
            summary = write_report(plan, run, outcome.error_code, outcome.error_string, sub,
                                   render=bool(params.get('render', True)) and i == 0)
            if part is not None:
                summary['part'] = part.describe()
            results.append((plan, run, outcome, summary))
            print(_bead_line(f'bead ({method})', summary.get('bead')), flush=True)
            if not outcome.succeeded:
                break
        main_plan, main_run, outcome, summary = results[0]
        executed = summary.get('executed', {})
        if 'note' in executed:
            print(f"executed: {executed['note']} ({executed['samples']} samples)")
        elif executed:
            print(f"executed: speed within 1 % on {100 * executed['fraction_within_1pct']:.1f} % of the bead, "
                  f"max tip deviation {executed['max_tip_deviation_mm']:.3f} mm, max joint tracking error "
                  f"{1e3 * executed['max_joint_tracking_error_rad']:.3f} mrad")
        finish_report(results, out_dir, video=bool(params.get('video', True)), video_fps=video_fps)
        print(f'report: {(out_dir / "index.html").resolve()}', flush=True)
        return 0 if all(r[2].succeeded for r in results) else 5
    finally:
        ur.close()


VIDEO_FPS = 30  # frames per second of robot time in the run's video, unless `video_fps` says otherwise


def _video_fps(value) -> int:
    """The `video_fps` parameter, checked: a whole number of frames per second of robot time in [1, 60]."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value) \
            or not 1 <= value <= 60:
        raise JobError(f'video_fps: {value!r} is not a whole number of frames per second in [1, 60]')
    return int(value)


def finish_report(results: list, out_dir: Path, video: bool = True, video_fps: int = VIDEO_FPS) -> dict:
    """The parts that span the runs: the bead figures side by side, the video (`video_fps` frames per second of
    robot time), index.html; summary.json again."""
    plan, run, _, summary = results[0]
    if len(results) > 1:
        base = results[1]
        summary['baseline'] = {k: base[3].get(k) for k in ('method', 'bead', 'planned', 'executed', 'dispenser',
                                                           'result')}
        summary['baseline']['report_dir'] = base[0].method
    beads = []
    for p, r, _, _ in results:
        analysed = analyse_bead(p, r)
        if analysed is not None:
            beads.append((LABELS.get(p.method, p.method), analysed[1], analysed[0]))
    images = []
    if beads:
        write_bead_figure(beads, out_dir / 'bead.png')
        images.append(('The bead on the glass: width along it and its centre against the line, per method',
                       'bead.png'))
    movie = None
    if video and run is not None and run.whole is not None and len(run.whole.t) > 1:
        print(f'rendering the video (MuJoCo off-screen, {video_fps} fps of robot time):', flush=True)
        info = render_video(plan.robot, plan.tool, scene_meshes(plan), run.whole.t, run.whole.q,
                            out_dir / 'run.mp4', bead=run.deposit, bead_t0=run.whole_t0, fps=video_fps)
        summary['video'] = {'file': 'run.mp4', **info}
        print(f"video: {info['frames']} frames, {info['duration_s']:.1f} s, rendered in "
              f"{info['render_seconds']:.1f} s", flush=True)
        movie = 'run.mp4'
    for caption, name in (('Tip speed along the bead, planned and executed (ours)', 'tcp_speed.png'),
                          ("Tip speed, seed 1's method", 'seed1/tcp_speed.png'),
                          ('The arm over the windshield with the tip paths', 'render.png'),
                          ('Tip path on the windshield', 'tip_path_3d.png'),
                          ('Planned and measured joint positions', 'joint_position_planned_vs_measured.png'),
                          ('Joint velocity', 'joint_velocity.png'), ('Joint acceleration', 'joint_acceleration.png')):
        if (out_dir / name).is_file():
            images.append((caption, name))
    (out_dir / 'summary.json').write_text(json.dumps(summary, indent=2))
    write_index(out_dir, summary, images, movie)
    return summary


def main(argv: list[str] | None = None) -> int:
    """One job, as `ur_glue_planner --ros-args ...` runs it (ur_glue_planner/parts/command.py dispatches)."""
    params, stop = start_ros('ur_glue_planner', argv)
    try:
        return run_job(params, stop, context=rclpy.get_default_context())
    except KeyboardInterrupt:
        return 130
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    sys.exit(main())
