"""Seed 2, tasks 12 and 14: two via points at 2.5 s and 6.0 s, stopping at the first (12) or passing it with
velocity [-0.4 0 0 -0.3 0 0] (14). Sent on the topic, recorded at 50 Hz.

Usage: python examples/seed2_via_points.py --task 12|14
"""
from __future__ import annotations

import argparse

import numpy as np
import seed2_common as seed

from ur_glue_planner.report.plots import plot_joint_states


def run(ur, out_dir, task: str = '12') -> dict:
    q_target = seed.target_configuration(ur)
    q_points = np.vstack([q_target, seed.QF])
    qvel = np.zeros((2, 6)) if task == '12' else np.vstack([seed.QVEL_TASK14, np.zeros(6)])
    seed.go_home(ur)
    t0 = seed.start_time(ur)
    recorder = ur.start_recording(seed.RATE, t0)
    ur.publish_trajectory(seed.VIA_TIMES, q_points, qvel, start_time=t0)
    duration = seed.VIA_TIMES[-1] + seed.T_OFFSET
    ur.sleep(t0 - ur.now() + duration)
    rec = ur.stop_recording(recorder, duration)
    pngs = plot_joint_states(rec.t, rec.q, rec.qd, ur.joint_names, out_dir, f'task{task}',
                             f'Task {task}: via points')
    at_via = int(np.argmin(np.abs(rec.t - seed.VIA_TIMES[0])))
    # Slowest speed of each joint within 0.25 s of the via point: ~0 where a joint stops there.
    near = np.abs(rec.t - seed.VIA_TIMES[0]) <= 0.25
    slowest = np.abs(rec.qd[near]).min(axis=0)
    print(f'task {task}: joint velocities at the via point (t = {rec.t[at_via]:.2f} s): {np.round(rec.qd[at_via], 3)}')
    print(f'task {task}: slowest joint speeds within 0.25 s of the via point: {np.round(slowest, 3)} rad/s')
    final_error = float(np.abs(rec.q[-1] - seed.QF).max())
    return {'recording': rec, 'velocity_at_via': rec.qd[at_via], 'slowest_near_via': slowest,
            'final_error': final_error, 'plots': pngs}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--task', choices=['12', '14'], default='12')
    parser.add_argument('--out', default='out/seed2')
    parser.add_argument('--timeout', type=float, default=15.0)
    args = parser.parse_args()
    with seed.connect(args.timeout) as ur:
        result = run(ur, args.out, args.task)
    return 0 if result['final_error'] < 0.01 else 1


if __name__ == '__main__':
    raise SystemExit(main())
