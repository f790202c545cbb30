"""Seed 2, tasks 4-10: home, then point-to-point to the IK target on the JointTrajectory topic, recorded at 50 Hz.

Usage: python examples/seed2_topic_p2p.py [--out out/seed2]
"""
from __future__ import annotations

import numpy as np
import seed2_common as seed

from ur_glue_planner.report.plots import plot_joint_states


def run(ur, out_dir) -> dict:
    q_target = seed.target_configuration(ur)
    seed.go_home(ur)
    t0 = seed.start_time(ur)
    recorder = ur.start_recording(seed.RATE, t0)
    ur.publish_trajectory([seed.T_TARGET], q_target[None, :], np.zeros((1, 6)), start_time=t0)
    ur.sleep(t0 - ur.now() + seed.T_TARGET + seed.T_OFFSET)
    rec = ur.stop_recording(recorder, seed.T_TARGET + seed.T_OFFSET)
    pngs = plot_joint_states(rec.t, rec.q, rec.qd, ur.joint_names, out_dir, 'topic_p2p', 'Point to point (topic)')
    error = float(np.abs(rec.q[-1] - q_target).max())
    print(f'{len(rec.t)} samples at {seed.RATE:.0f} Hz; final error {error:.2e} rad; '
          f'plots: {", ".join(map(str, pngs))}')
    return {'recording': rec, 'q_target': q_target, 'final_error': error, 'plots': pngs}


def main() -> int:
    args = seed.parse_args(__doc__)
    with seed.connect(args.timeout) as ur:
        result = run(ur, args.out)
    return 0 if result['final_error'] < 0.01 else 1


if __name__ == '__main__':
    raise SystemExit(main())
