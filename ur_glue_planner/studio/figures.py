"""The seed's four figures of a plan as images for the page: planned joint positions, velocities, accelerations
(one subplot per joint) and the tip's linear speed, plus the headline speed figures as text."""
from __future__ import annotations

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ur_glue_planner.motion.plan import GluePlan  # noqa: E402

FIGURES = ('joint position', 'joint velocity', 'joint acceleration', 'tcp speed')


def _to_image(fig) -> np.ndarray:
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    plt.close(fig)
    return image


def _joint_figure(t: np.ndarray, values: np.ndarray, names, title: str, unit: str) -> np.ndarray:
    fig, axes = plt.subplots(2, 3, figsize=(7.2, 4.2), dpi=80, constrained_layout=True)
    for j, ax in enumerate(axes.flat):
        ax.plot(t, values[:, j], lw=1.2)
        ax.set_title(names[j], fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.4)
        ax.set_xlabel('time [s]', fontsize=7)
        ax.set_ylabel(unit, fontsize=7)
    fig.suptitle(title, fontsize=10)
    return _to_image(fig)


def plan_figures(plan: GluePlan) -> dict[str, np.ndarray]:
    """RGB images (H, W, 3) uint8 of the seed's four figures of the planned bead, keyed by :data:`FIGURES`."""
    bead = plan.bead
    names = list(bead.joint_names)
    out = {
        'joint position': _joint_figure(bead.times, bead.q, names, 'Desired joint position', 'rad'),
        'joint velocity': _joint_figure(bead.times, bead.qd, names, 'Desired joint velocity', 'rad/s'),
        'joint acceleration': _joint_figure(bead.times, bead.qdd, names, 'Desired joint acceleration', 'rad/s^2'),
    }
    fig, ax = plt.subplots(figsize=(7.2, 3.0), dpi=80, constrained_layout=True)
    ax.plot(bead.times, bead.tcp_speed, lw=1.2, label='planned')
    ax.axhline(plan.job.tcp_speed, color='k', lw=0.8, ls='--', label='commanded')
    ax.set(title='Desired end-effector (tip) linear speed', xlabel='time [s]', ylabel='speed [m/s]')
    ax.grid(True, lw=0.4)
    ax.legend(fontsize=8)
    out['tcp speed'] = _to_image(fig)
    return out


def speed_summary(plan: GluePlan) -> str:
    """Markdown lines with the planned TCP speed figures and the plan's size."""
    s = plan.summary
    return (f'**Bead** {s.bead_length:.3f} m in {s.bead_duration:.2f} s (total {s.total_duration:.2f} s)  \n'
            f'**Planned TCP speed** mean {s.speed_mean:.4f}, min {s.speed_min:.4f}, max {s.speed_max:.4f} m/s '
            f'(commanded {plan.job.tcp_speed:.3f})  \n'
            f'**Within 1 %** on {100 * s.within_1pct:.1f} % of the bead; {s.slowdowns} slowdown(s); '
            f'peak joint speed {100 * s.max_velocity_usage:.0f} % of the limit  \n'
            f'planned in {1e3 * s.planning_seconds:.0f} ms')
