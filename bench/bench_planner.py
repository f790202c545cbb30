"""Glue planner benchmark: planning time of the default job, and executed speed uniformity and tip deviation
on ur_sim (its own process, real time). Writes out/bench/planner.json (through `python -m bench`)."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import tempfile
import threading
from pathlib import Path

import numpy as np
import rclpy

from ur_glue_planner.execution.node import run_job
from ur_glue_planner.job import default_job_path, load_job
from ur_glue_planner.motion.plan import plan_job

CONFIG = Path(__file__).resolve().parents[1] / 'config'


def planning_times(repeats: int = 5) -> dict:
    job = load_job(default_job_path())
    home = np.array(job.home)
    plans = [plan_job(job, home) for _ in range(repeats)]
    ik = [p.bead.ik_seconds for p in plans]
    total = [p.summary.planning_seconds for p in plans]
    return {'repeats': repeats, 'bead_samples': int(len(plans[0].bead.times)),
            'ik_all_samples_ms': {'median': 1e3 * float(np.median(ik)), 'min': 1e3 * min(ik)},
            'plan_job_ms': {'median': 1e3 * float(np.median(total)), 'min': 1e3 * min(total)},
            'target_ik_ms': 100.0}


def executed_on_sim() -> dict:
    sim = subprocess.Popen(['ur_sim', '--ros-args', '--params-file', str(CONFIG / 'ur_sim_windshield.yaml')],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        rclpy.init()
        with tempfile.TemporaryDirectory() as out:
            code = run_job({'job': str(default_job_path()), 'out_dir': out, 'render': False}, threading.Event())
            summary = json.loads((Path(out) / 'summary.json').read_text()) if code in (0, 5) else {}
    finally:
        rclpy.try_shutdown()
        os.killpg(sim.pid, signal.SIGINT)
        sim.wait(timeout=20)
    executed = summary.get('executed', {})
    return {'exit_code': code, 'real_time_factor': 1.0, 'result': summary.get('result'),
            'planned_fraction_within_1pct': summary.get('planned', {}).get('fraction_within_1pct'),
            'executed_fraction_within_1pct': executed.get('fraction_within_1pct'),
            'executed_speed_m_s': executed.get('tcp_speed_m_s'),
            'max_tip_deviation_mm': executed.get('max_tip_deviation_mm'),
            'max_joint_tracking_error_mrad': 1e3 * executed.get('max_joint_tracking_error_rad', float('nan')),
            'targets': {'fraction_within_1pct': 0.95, 'max_tip_deviation_mm': 0.5}}


def run() -> dict:
    return {'planning': planning_times(), 'execution': executed_on_sim()}
