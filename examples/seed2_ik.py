"""Seed 2, task 3: inverse kinematics of the UR10's ee_link to the seed's target pose.

Usage: python examples/seed2_ik.py   (with ur_sim running the seed_ur10 preset)
"""
from __future__ import annotations

import numpy as np
import seed2_common as seed


def run(ur, out_dir=None) -> dict:
    q = seed.target_configuration(ur)
    difference = np.abs(q - seed.SEED_IK_ANSWER)
    print('joint            ours      seed')
    for name, a, b in zip(ur.joint_names, q, seed.SEED_IK_ANSWER):
        print(f'{name:20s} {a:8.4f} {b:8.4f}')
    print(f'max difference to the seed answer: {difference.max():.2e} rad')
    return {'q': q, 'max_difference': float(difference.max())}


def main() -> int:
    args = seed.parse_args(__doc__)
    with seed.connect(args.timeout) as ur:
        result = run(ur)
    return 0 if result['max_difference'] < 1e-3 else 1


if __name__ == '__main__':
    raise SystemExit(main())
