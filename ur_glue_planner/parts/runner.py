"""``ur_glue_planner --parts N --seed S``: the glue job on N generated windshields, each with and without correction.

Per part: the part is generated (``scene/part_variation.py``) and written as a scene (``scene/part_scene.py``);
ur_sim starts on it in a process of its own (the job's simulator parameters, ``scene:=<part>/scene.yaml``, as fast
as it runs in step with this client (``pace_topic``, see ``PACE_TOPIC``), the scanners' noise seeded by the part),
on a ROS domain of its own; then

1. **corrected**: the scan is read and fitted; a part outside what the cell corrects, or whose corrected bead is out
   of reach, is refused with the reason and nothing is dispensed; else the bead is planned on the measured part and
   run;
2. **uncorrected**: the bead planned on the nominal glass is run on the same part (what a cell without measuring
   lays).

Both beads are judged against the line where the bead belongs on that part (``judge.py``) and written to
``<out>/part_NNN/result.json``, each run recorded as a rosbag2 in ``bag_corrected`` / ``bag_uncorrected`` beside it
(``--no-bags``: not recorded); ur_sim is stopped. Parts run ``--jobs`` at a time, each worker a process of its
own (``--worker k/K``) on a ROS domain of its own (ROS_DOMAIN_ID + k); the runner prints a line per part as it
finishes and writes ``<out>/summary.json`` and ``<out>/index.html`` at the end. Exit codes: 0 every accepted part
met the goal with correction, 1 one did not (or a part was not run), 2 bad arguments, 130 interrupted.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
import traceback
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import rclpy
from rclpy.context import Context

from ur_common.paths import config_dir
from ur_glue_planner.errors import ClientError, JobError, PlanningError
from ur_glue_planner.execution.bead_listener import BeadListener
from ur_glue_planner.execution.client import URClient
from ur_glue_planner.execution.dispenser_io import OutputChange, dispenser_for
from ur_glue_planner.execution.part_measure import describe as describe_part
from ur_glue_planner.execution.part_measure import measure_part, read_scan
from ur_glue_planner.execution.run import Interrupted, dispenser_events, execute
from ur_glue_planner.job import GlueJob, default_job_path, load_job
from ur_glue_planner.motion.plan import GluePlan, plan_job
from ur_glue_planner.parts.judge import MODES, meets_goal, refused, run_figures, summarize
from ur_glue_planner.parts.page import write_page
from ur_glue_planner.report.bead_report import analyse_bead
from ur_glue_planner.scene.part_scene import write_part_scene
from ur_glue_planner.scene.part_variation import Part, VariationLimits, make_part
from ur_glue_planner.scene.waypoints import windshield_model

SIM_PARAMS = 'ur_sim_windshield.yaml'
PORTS = ('dashboard_server', 'rtde', 'primary', 'secondary', 'realtime')  # on free ports: parts never share one
STARTUP_TIMEOUT = 60.0  # [s] of wall time for ur_sim to come up on a loaded machine
# ur_sim runs as fast as it can, in step with this client (pace_topic): it never gets more than pace_lag of robot
# time ahead of the client's view, and holds while a gun switch is on its way, so the bead's start and end are
# where they would be on a robot at real time, however loaded the machine is. Free-running instead, the set_io
# latency becomes robot time times the speed-up (15 mm of bead at full speed, 55 mm under load at 4x).
REAL_TIME_FACTOR = 0.0
PACE_TOPIC = '/ur_sim/pace'
# Without a ROS_DOMAIN_ID: 190 (worker 0), 191, ...: clear of the tests' 1..101 and the demo's 120..179.
DOMAIN_BASE = 190


@dataclass(frozen=True)
class PartsRun:
    """What to run: ``count`` parts of series ``seed`` within ``limits``, the job, where to write, the ROS domain."""

    count: int
    seed: int
    out_dir: Path
    job: GlueJob
    limits: VariationLimits
    domain_id: int
    real_time_factor: float = REAL_TIME_FACTOR
    bags: bool = True  # each run recorded as a rosbag2 (MCAP) in part_NNN/bag_corrected and bag_uncorrected


@contextmanager
def simulator(scene: Path, seed: int, domain_id: int, log: Path, real_time_factor: float):
    """ur_sim on ``scene`` in its own process group and domain, at ``real_time_factor``; stopped on exit (SIGINT,
    then SIGKILL after 10 s)."""
    args = ['ur_sim', '--ros-args', '--params-file', str(config_dir() / SIM_PARAMS), '-p', f'scene:={scene}',
            '-p', f'real_time_factor:={real_time_factor}', '-p', f'part_scan_seed:={seed}', '-p',
            f'pace_topic:={PACE_TOPIC}']
    for port in PORTS:
        args += ['-p', f'{port}.port:=0']
    env = {**os.environ, 'ROS_DOMAIN_ID': str(domain_id)}
    with open(log, 'w') as out:
        proc = subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        yield proc
    finally:
        _stop_group(proc)


def _stop_group(proc: subprocess.Popen, timeout: float = 10.0) -> None:
    """SIGINT to the process group (ur_sim and its trajectory gateway), SIGKILL to what is left after ``timeout``
    [s]; returns when the whole group is gone, so the next part's ur_sim meets nothing of this one in the domain."""
    deadline = time.monotonic() + timeout
    try:
        os.killpg(proc.pid, signal.SIGINT)
    except ProcessLookupError:
        return
    while True:
        proc.poll()  # reaps the leader once it exited
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            return
        if time.monotonic() > deadline:
            os.killpg(proc.pid, signal.SIGKILL)
            deadline = float('inf')
        time.sleep(0.05)  # a process's exit is not a ROS event; polling it is the only way to see it


def _judged(plan: GluePlan, run, outcome, part: Part, nominal_plan: GluePlan) -> dict:
    """A run's figures against where the bead belongs on the part: the nominal line carried onto its glass."""
    nominal = windshield_model(nominal_plan.job.windshield)
    intended = (part.on_part(nominal.project(nominal_plan.line)[1]),
                part.on_part(nominal.project(nominal_plan.waypoints)[1]))
    analysed = analyse_bead(plan, run, intended=intended)
    figures = run_figures(analysed[0] if analysed else None, outcome.error_code, outcome.error_string)
    figures['gun_late_ms'] = gun_lateness(plan, run)
    return figures


def gun_lateness(plan: GluePlan, run) -> dict:
    """How late [ms of trajectory time] the output showed each planned switch on io_states: the service's latency
    as the robot's clock saw it (a few ms on a real robot; times the real-time factor here)."""
    changes = [c for c in (run.switches if run is not None else ()) if isinstance(c, OutputChange)]
    out = {}
    for event in dispenser_events(plan):
        seen = [c.trajectory_time for c in changes if c.state == event.state and c.trajectory_time is not None]
        out[event.what] = round(1e3 * (min(seen) - event.t), 1) if seen else None
    return out


def run_part(config: PartsRun, index: int, nominal_plan: GluePlan, stop: threading.Event) -> dict:
    """Generate, simulate, measure, run twice and judge part ``index``; returns its record for summary.json."""
    job = config.job
    part = make_part(windshield_model(job.windshield), config.seed, index, config.limits)
    record: dict = {'index': index, 'part': part.describe(), 'measured': None, 'seconds': {}}
    clock = [time.monotonic()]

    def lap(what: str) -> None:  # wall time of each stage [s], for the performance page
        now = time.monotonic()
        record['seconds'][what] = round(now - clock[0], 2)
        clock[0] = now
    folder = config.out_dir / f'part_{index:03d}'
    scene = write_part_scene(part, folder / 'scene')
    lap('scene')
    domain = config.domain_id  # the worker's own: the previous part's processes are gone (_stop_group)
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    log_file = open(folder / 'run.log', 'w')  # the runs' progress lines: the terminal gets one line per part

    def log(text: str) -> None:
        log_file.write(text + '\n')
        log_file.flush()
    try:
        with simulator(scene, index, domain, folder / 'ur_sim.log', config.real_time_factor):
            ur = URClient(controller_name=job.controller_name, timeout=STARTUP_TIMEOUT, context=context,
                          node_name='ur_glue_parts')
            try:
                gun = dispenser_for(ur.node, '', job.controller_name, pace_topic=PACE_TOPIC)
                gun.follow_joint_states(ur.on_joint_state)
                bead = BeadListener(ur.node)
                if not (gun.available(timeout=STARTUP_TIMEOUT) and bead.available(timeout=STARTUP_TIMEOUT)):
                    raise ClientError('ur_sim has no set_io or no glue bead service')
                lap('start')
                profiles = read_scan(ur.node, timeout=STARTUP_TIMEOUT)
                if profiles is None:
                    raise ClientError('no part scan on /ur_sim/part_scan')
                found, reason = measure_part(profiles, nominal_plan.surface)
                if found is not None:
                    record['measured'] = found.describe()
                    log(describe_part(found))
                lap('measure')
                plan = None
                if reason is None:
                    try:
                        plan = plan_job(job, ur.joint_state().q, part=found)
                    except PlanningError as exc:
                        reason = f'the corrected bead cannot be planned: {exc}'
                if plan is None:
                    log(f'part refused, nothing dispensed: {reason}')
                    record['corrected'] = refused(reason)
                else:
                    lap('plan')
                    outcome, run = execute(ur, plan, stop, log=log, gun=gun, bead=bead, record=config.bags,
                                           bag_dir=folder / 'bag_corrected')
                    lap('corrected')
                    record['corrected'] = _judged(plan, run, outcome, part, nominal_plan)
                    lap('judge')
                plan = plan_job(job, ur.joint_state().q)
                lap('plan_nominal')
                outcome, run = execute(ur, plan, stop, log=log, gun=gun, bead=bead, record=config.bags,
                                       bag_dir=folder / 'bag_uncorrected')
                lap('uncorrected')
                record['uncorrected'] = _judged(plan, run, outcome, part, nominal_plan)
                lap('judge_uncorrected')
            finally:
                ur.close()
    finally:
        rclpy.try_shutdown(context=context)
        log_file.close()
    (folder / 'result.json').write_text(json.dumps(record, indent=2))
    return record


def _line(record: dict) -> str:
    if 'error' in record:
        return f"part {record['index']:3d}: failed, not judged: {record['error']}"

    def one(mode: str) -> str:
        r = record[mode]
        if r['refused'] is not None:
            return f"{mode}: refused ({r['refused']})"
        if r['lateral_p95_mm'] is None:
            return f"{mode}: no bead on the line (error_code {r['error_code']})"
        return (f"{mode}: lateral p95 {r['lateral_p95_mm']:.3f} mm, max {r['lateral_max_mm']:.3f} mm, gaps "
                f"{r['gaps']}, width within 5 % {100 * r['width_within_5pct']:.1f} %"
                + ('' if r['error_code'] == 0 else f" (error_code {r['error_code']})"))
    p = record['part']
    return (f"part {record['index']:3d} (offset {p['offset_mm']} mm, turned {p['rotation_deg']} deg, bent "
            f"{p['shape_amplitude_mm']:.2f} mm): " + '; '.join(one(m) for m in MODES))


def run_worker(config: PartsRun, worker: int, workers: int, stop: threading.Event) -> int:
    """Parts ``worker``, ``worker + workers``, ... in turn, each's record in part_NNN/result.json."""
    nominal_plan = plan_job(config.job, config.job.home)
    for index in range(worker, config.count, workers):
        if stop.is_set():
            return 130
        try:
            run_part(config, index, nominal_plan, stop)
        except Interrupted:
            return 130
        except Exception as exc:  # noqa: BLE001 - one part's failure is reported, and the next part runs
            folder = config.out_dir / f'part_{index:03d}'
            folder.mkdir(parents=True, exist_ok=True)
            (folder / 'result.json').write_text(json.dumps({'index': index, 'error': f'{type(exc).__name__}: {exc}',
                                                            'traceback': traceback.format_exc()}, indent=2))
    return 0


def _worker_command(config: PartsRun, args: argparse.Namespace, worker: int, workers: int) -> list[str]:
    command = [sys.executable, '-m', 'ur_glue_planner.parts.command', '--parts', str(config.count), '--seed',
               str(config.seed), '--out', str(config.out_dir), '--placement-mm', str(args.placement_mm),
               '--rotation-deg', str(args.rotation_deg), '--shape-mm', str(args.shape_mm), '--real-time-factor',
               str(config.real_time_factor), '--worker', f'{worker}/{workers}']
    return command + (['--job', args.job] if args.job else []) + ([] if config.bags else ['--no-bags'])


def _mm(value: float | None) -> str:
    return 'none (no part accepted)' if value is None else f'{value:.2f} mm'


def write_summary(config: PartsRun, records: list[dict], seconds: float, failed: list[dict]) -> dict:
    """summary.json and index.html from the judged parts (and the ones that failed, with why)."""
    summary = summarize(records)
    summary['failed'] = failed
    summary['seed'], summary['limits'] = config.seed, vars(config.limits)
    summary['real_time_factor'], summary['wall_seconds'] = config.real_time_factor, round(seconds, 1)
    (config.out_dir / 'summary.json').write_text(json.dumps(summary, indent=2))
    write_page(config.out_dir, summary)
    return summary


def run_parts(config: PartsRun, args: argparse.Namespace, workers: int, stop: threading.Event) -> int:
    """Every part, ``workers`` at a time (each worker a process of its own with its own ROS domains); a line per
    part as it finishes; summary.json and index.html at the end. Returns the exit code."""
    config.out_dir.mkdir(parents=True, exist_ok=True)
    for old in config.out_dir.glob('part_*/result.json'):
        old.unlink()
    t0 = time.monotonic()
    procs = []
    for k in range(workers):
        env = {**os.environ, 'ROS_DOMAIN_ID': str(config.domain_id + k)}
        procs.append(subprocess.Popen(_worker_command(config, args, k, workers), env=env, start_new_session=True))
    records: dict[int, dict] = {}
    try:
        while len(records) < config.count and not stop.is_set():
            for index in range(config.count):
                path = config.out_dir / f'part_{index:03d}' / 'result.json'
                if index not in records and path.is_file():
                    records[index] = json.loads(path.read_text())
                    print(f'{_line(records[index])} [{time.monotonic() - t0:.0f} s]', flush=True)
            if all(p.poll() is not None for p in procs) and len(records) < config.count:
                break  # a worker died: what it did not do is missing from the summary (its exit status says so)
            stop.wait(0.5)
    finally:
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
        for p in procs:
            try:
                p.wait(timeout=30.0)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
    if stop.is_set():
        return 130
    done = [records[i] for i in sorted(records) if 'error' not in records[i]]
    failed = [{'index': i, 'error': records[i]['error']} for i in sorted(records) if 'error' in records[i]]
    summary = write_summary(config, done, time.monotonic() - t0, failed)
    c = summary['corrected']
    print(f"{len(done)} of {config.count} parts in {summary['wall_seconds']:.0f} s. Corrected: {c['meeting_goal']} of "
          f"{c['accepted']} accepted parts meet the goal, {c['refused']} refused; worst lateral p95 "
          f"{_mm(c['lateral_p95_mm'])}. Report: {(config.out_dir / 'index.html').resolve()}", flush=True)
    if len(done) < config.count:
        print(f'ur_glue_planner: {config.count - len(done)} parts were not judged ({len(failed)} failed, see '
              f'summary.json "failed"; worker exit status {[p.returncode for p in procs]})', file=sys.stderr)
        return 1
    accepted = [r['corrected'] for r in done if r['corrected']['refused'] is None]
    return 0 if all(meets_goal(r) for r in accepted) else 1


def parse(argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The parts options, and the rest (``--ros-args ...``)."""
    p = argparse.ArgumentParser(prog='ur_glue_planner', description='Run the glue job on generated parts.')
    p.add_argument('--parts', type=int, required=True, help='how many parts (>= 1)')
    p.add_argument('--seed', type=int, default=1, help='series of parts (default 1)')
    p.add_argument('--out', default='out/parts', help='output folder (default out/parts)')
    p.add_argument('--job', default=None, help='glue job file (default config/glue_job.yaml)')
    p.add_argument('--placement-mm', type=float, default=4.0, help='placement error per axis [mm] (default 4)')
    p.add_argument('--rotation-deg', type=float, default=1.0, help='rotation error per axis [deg] (default 1)')
    p.add_argument('--shape-mm', type=float, default=2.0, help='shape deviation [mm] (default 2)')
    p.add_argument('--jobs', type=int, default=2, help='parts run at the same time (default 2)')
    p.add_argument('--real-time-factor', type=float, default=REAL_TIME_FACTOR,
                   help=f'ur_sim real_time_factor (default {REAL_TIME_FACTOR:g})')
    p.add_argument('--no-bags', dest='bags', action='store_false',
                   help='do not record the runs as rosbag2 (default: part_NNN/bag_corrected, bag_uncorrected)')
    p.add_argument('--worker', default=None, help=argparse.SUPPRESS)  # k/K: one of the runner's own processes
    return p.parse_known_args(argv)


def main(argv: list[str]) -> int:
    """Entry of ``ur_glue_planner --parts N [--seed S] ...``."""
    args, _ = parse(argv)
    try:
        if args.parts < 1:
            raise ValueError(f'--parts {args.parts} must be >= 1')
        if not 1 <= args.jobs <= 8:
            raise ValueError(f'--jobs {args.jobs} must be in [1, 8]')
        if not 0.0 <= args.real_time_factor <= 100.0:
            raise ValueError(f'--real-time-factor {args.real_time_factor} must be in [0, 100] (0: as fast as it runs)')
        limits = VariationLimits(args.placement_mm * 1e-3, args.rotation_deg, args.shape_mm * 1e-3)
        job = load_job(args.job or default_job_path())
    except (ValueError, JobError) as exc:
        print(f'ur_glue_planner: {exc}', file=sys.stderr)
        return 2
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    domain = int(os.environ.get('ROS_DOMAIN_ID', '') or DOMAIN_BASE)
    if args.worker is not None:
        worker, workers = (int(x) for x in args.worker.split('/'))
        config = PartsRun(args.parts, args.seed, Path(args.out), job, limits, domain, args.real_time_factor,
                          args.bags)
        return run_worker(config, worker, workers, stop)
    config = PartsRun(args.parts, args.seed, Path(args.out), job, limits, min(domain, 233 - args.jobs),
                      args.real_time_factor, args.bags)
    return run_parts(config, args, min(args.jobs, args.parts), stop)
