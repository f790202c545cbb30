"""Many glue jobs at once: N independent (ur_sim, ur_glue_planner) pairs, each in its own ROS domain, the
simulators as fast as possible. For users who validate many job variants: jobs per minute and each simulator's
real-time factor for N = 1, 2 and 4 (out/bench/scale.json through `python -m bench`).

Each pair is two processes, as users run them (`ur_sim` with the windshield scene, `ur_glue_planner` on the
default job without renders or video). A job's wall time runs from its planner's start to its exit (start-up, planning,
execution and report); its RTF is the simulated time over the wall time between two /clock samples taken by
this process when the planner starts and when it exits.
"""
from __future__ import annotations

import os
import platform
import subprocess
import tempfile
import time
from pathlib import Path

import rclpy
from rclpy.context import Context
from rclpy.node import Node

from bench.bench_sim import _clock_sample

CONFIG = Path(__file__).resolve().parents[1] / 'config'
FIRST_DOMAIN = 180  # above the test suite's 1..101, below DDS's 232
COUNTS = (1, 2, 4)


class _Domain:
    """ur_sim in domain `domain`, and a probe node there for /clock samples."""

    def __init__(self, domain: int) -> None:
        self.domain = domain
        self.env = {**os.environ, 'ROS_DOMAIN_ID': str(domain)}
        self.log = tempfile.TemporaryFile('w+')  # what ur_sim printed, for a failure's report
        self.sim = subprocess.Popen(
            ['ur_sim', '--ros-args', '--params-file', str(CONFIG / 'ur_sim_windshield.yaml'),
             '-p', 'real_time_factor:=0.0'],
            env=self.env, stdout=self.log, stderr=subprocess.STDOUT, start_new_session=True)
        self.ctx = Context()
        rclpy.init(context=self.ctx, domain_id=domain)
        self.node = Node(f'bench_scale_probe_{domain}', context=self.ctx)

    def clock(self) -> tuple[float, float]:
        try:
            return _clock_sample(self.node)
        except TimeoutError as exc:
            self.log.seek(0)
            state = 'running' if self.sim.poll() is None else f'exited with {self.sim.returncode}'
            raise TimeoutError(f'{exc} (domain {self.domain}, ur_sim {state}); it printed:\n'
                               f'{self.log.read()[-3000:]}') from exc

    def close(self) -> None:
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.ctx)
        if self.sim.poll() is None:
            os.killpg(self.sim.pid, 2)
        self.sim.wait(timeout=30)
        self.log.close()


def run_batch(n: int) -> dict:
    """N jobs started together; their wall times, RTFs and exit codes."""
    domains = [_Domain(FIRST_DOMAIN + k) for k in range(n)]
    try:
        for d in domains:
            d.clock()  # every simulator is up before the jobs start
        with tempfile.TemporaryDirectory() as tmp:
            logs = [open(Path(tmp) / f'job{k}.log', 'w+') for k in range(n)]
            t0 = time.perf_counter()
            starts = [d.clock() for d in domains]
            jobs = [subprocess.Popen(['ur_glue_planner', '--ros-args', '-p', f'out_dir:={tmp}/job{k}',
                                      '-p', 'render:=false', '-p', 'video:=false'],
                                     env=d.env, stdout=log, stderr=subprocess.STDOUT,
                                     cwd=tmp)
                    for k, (d, log) in enumerate(zip(domains, logs))]
            results = []
            for job, d, (w0, s0) in zip(jobs, domains, starts):
                code = job.wait(timeout=900)
                w1, s1 = d.clock()
                result = {'exit_code': code, 'wall_s': w1 - w0, 'sim_s': s1 - s0, 'rtf': (s1 - s0) / (w1 - w0)}
                if code != 0:  # what the planner and its simulator printed last
                    log = logs[len(results)]
                    log.seek(0)
                    result['output_tail'] = log.read()[-1500:]
                    d.log.seek(0)
                    result['sim_output_tail'] = d.log.read()[-3000:]
                results.append(result)
            for log in logs:
                log.close()
            batch_wall = time.perf_counter() - t0
    finally:
        for d in domains:
            d.close()
    ok = sum(r['exit_code'] == 0 for r in results)
    return {'jobs': n, 'succeeded': ok, 'batch_wall_s': batch_wall, 'jobs_per_minute': 60.0 * ok / batch_wall,
            'per_job': results}


def run() -> dict:
    batches = [run_batch(n) for n in COUNTS]
    one = batches[0]['jobs_per_minute']
    for b in batches:
        b['speed_up_vs_one'] = b['jobs_per_minute'] / one if one else None
    cores = os.cpu_count()
    return {
        'machine': {'cpus': cores, 'processor': platform.processor() or platform.machine(),
                    'python': platform.python_version()},
        'batches': batches,
        'scaling': '; '.join(
            f"N={b['jobs']}: {b['jobs_per_minute']:.1f} jobs/min (x{b['speed_up_vs_one']:.2f}), RTF per simulator "
            f"{min(r['rtf'] for r in b['per_job']):.1f}-{max(r['rtf'] for r in b['per_job']):.1f}"
            for b in batches) + f' on {cores} cores',
    }


if __name__ == '__main__':
    import json
    out = Path(__file__).resolve().parents[1] / 'out' / 'bench'
    out.mkdir(parents=True, exist_ok=True)
    (out / 'scale.json').write_text(json.dumps(run(), indent=2))
