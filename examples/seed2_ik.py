"""Seed 2, task 3: inverse kinematics of the UR10's ee_link to the seed's target pose.

Usage: python examples/seed2_ik.py   (with ur_sim running the seed_ur10 preset)
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import seed2_common as seed  # noqa: E402


def plot_comparison(names, ours, theirs, path: Path) -> Path:
    """Bar chart of the joint solution against the seed's answer."""
    fig, ax = plt.subplots(figsize=(8, 4), constrained_layout=True)
    x = np.arange(len(names))
    ax.bar(x - 0.2, ours, 0.4, label='ur_sim_driver (Pinocchio)')
    ax.bar(x + 0.2, theirs, 0.4, label='seed (MATLAB)')
    ax.set_xticks(x, [n.replace('_joint', '') for n in names])
    ax.set_ylabel('joint position [rad]')
    ax.set_title('IK of ee_link to the seed target')
    ax.legend()
    ax.grid(True, axis='y')
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def run(ur, out_dir=None) -> dict:
    q = seed.target_configuration(ur)
    difference = np.abs(q - seed.SEED_IK_ANSWER)
    print('joint            ours      seed')
    for name, a, b in zip(ur.joint_names, q, seed.SEED_IK_ANSWER):
        print(f'{name:20s} {a:8.4f} {b:8.4f}')
    print(f'max difference to the seed answer: {difference.max():.2e} rad')
    pngs = [] if out_dir is None else [plot_comparison(ur.joint_names, q, seed.SEED_IK_ANSWER,
                                                        Path(out_dir) / 'ik_comparison.png')]
    return {'q': q, 'max_difference': float(difference.max()), 'plots': pngs}


def main() -> int:
    args = seed.parse_args(__doc__)
    with seed.connect(args.timeout) as ur:
        result = run(ur, args.out)
    return 0 if result['max_difference'] < 1e-3 else 1


if __name__ == '__main__':
    raise SystemExit(main())
