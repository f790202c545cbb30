"""Seed 2, task 20: FollowJointTrajectory without blocking; joint states are recorded at 50 Hz and the feedback
is monitored while the robot moves, then plotted.

Usage: python examples/seed2_action_monitor.py [--out out/seed2]
"""
from __future__ import annotations

import numpy as np
import seed2_common as seed

from ur_glue_planner.report.plots import plot_joint_states


def run(ur, out_dir) -> dict:
    q_target = seed.target_configuration(ur)
    seed.go_home(ur)
    feedback_errors = []
    t0 = seed.start_time(ur)
    recorder = ur.start_recording(seed.RATE, t0)
    goal = ur.follow_trajectory(np.vstack([q_target, seed.QF]), np.zeros((2, 6)), None, seed.VIA_TIMES, wait=False,
                                start_time=t0,
                                feedback_callback=lambda fb: feedback_errors.append(max(map(abs, fb.error.positions))))
    print('goal sent; the script keeps running while the robot moves')
    outcome = goal.wait()
    # Until the joint states received reach the trajectory's end (the result can arrive before the last of them).
    ur.sleep(max(0.0, t0 + seed.VIA_TIMES[-1] - ur.now()) + seed.T_OFFSET)
    rec = ur.stop_recording(recorder)
    pngs = plot_joint_states(rec.t, rec.q, rec.qd, ur.joint_names, out_dir, 'action_monitor',
                             'FollowJointTrajectory (non-blocking)')
    print(f'{outcome.status} (error_code {outcome.error_code}); {len(feedback_errors)} feedback messages, '
          f'max tracking error {max(feedback_errors, default=0.0):.2e} rad; plots: {", ".join(map(str, pngs))}')
    return {'outcome': outcome, 'recording': rec, 'feedback_errors': feedback_errors, 'plots': pngs}


def main() -> int:
    args = seed.parse_args(__doc__)
    with seed.connect(args.timeout) as ur:
        result = run(ur, args.out)
    return 0 if result['outcome'].succeeded else 1


if __name__ == '__main__':
    raise SystemExit(main())
