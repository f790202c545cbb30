"""Seed 2, tasks 16-19: FollowJointTrajectory, blocking, with per-joint path and goal tolerances and a
goal_time_tolerance of 10 ms; the result's error code is checked.

Usage: python examples/seed2_action_blocking.py [--qtol 0.05]
"""
from __future__ import annotations

import argparse

import numpy as np
import seed2_common as seed

from ur_glue_planner.report.plots import plot_joint_states


def run(ur, out_dir=None, qtol: float = 0.05, qveltol: float = 0.5, qacctol: float = 0.0) -> dict:
    q_target = seed.target_configuration(ur)
    seed.go_home(ur)
    tolerances = ur.tolerances(qtol, qveltol, qacctol)
    t0 = seed.start_time(ur)
    recorder = ur.start_recording(seed.RATE, t0)
    outcome = ur.follow_trajectory(np.vstack([q_target, seed.QF]), np.zeros((2, 6)), None, seed.VIA_TIMES,
                                   path_tolerance=tolerances, goal_tolerance=tolerances, goal_time_tolerance=0.010,
                                   start_time=t0)
    ur.sleep(max(0.0, t0 - ur.now()) + seed.T_OFFSET)  # also record how the robot holds after the result
    rec = ur.stop_recording(recorder)
    pngs = []
    if out_dir is not None:
        pngs = plot_joint_states(rec.t, rec.q, rec.qd, ur.joint_names, out_dir, f'action_blocking_qtol{qtol:g}',
                                 f'FollowJointTrajectory (blocking, qtol {qtol:g} rad)')
    if outcome.error_code:
        print(f'Arm motion error: error_code {outcome.error_code}: {outcome.error_string}')
    else:
        print(f'UR arm motion completed with state {outcome.status}.')
    return {'outcome': outcome, 'q': ur.joint_state().q, 'recording': rec, 'plots': pngs}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--qtol', type=float, default=0.05, help='position tolerance [rad]')
    parser.add_argument('--out', default='out/seed2')
    parser.add_argument('--timeout', type=float, default=15.0)
    args = parser.parse_args()
    with seed.connect(args.timeout) as ur:
        result = run(ur, args.out, qtol=args.qtol)
    return 0 if result['outcome'].succeeded else 1


if __name__ == '__main__':
    raise SystemExit(main())
