"""The seed's four figures of a plan as images for the page: planned joint positions, velocities, accelerations
(one subplot per joint) and the tip's linear speed, plus the headline speed figures as text.

The figures show the bead; the page's time slider covers the whole job (approach, descent, bead, retreat). So that
the two can be compared, each figure's lower axis is the time from the bead's start and its upper axis the job's
time, which the slider shows.
"""
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


BEAD_AXIS = 'bead time [s]'
JOB_AXIS = 'job time [s] (the slider)'


def bead_window(plan: GluePlan) -> tuple[float, float]:
    """(start, end) [s] of the bead in the job's time (from the start of the first segment, as the slider)."""
    start = 0.0
    for seg in plan.segments():
        if seg.name == 'bead':
            return start, start + seg.duration
        start += seg.duration
    raise ValueError('the plan has no bead segment')


def _job_axis(ax, offset: float, fontsize: int) -> None:
    """An upper axis in job time [s] over a lower one in bead time."""
    top = ax.secondary_xaxis('top', functions=(lambda t: t + offset, lambda t: t - offset))
    top.set_xlabel(JOB_AXIS, fontsize=fontsize)
    top.tick_params(labelsize=fontsize)


def _joint_figure(t: np.ndarray, values: np.ndarray, names, title: str, unit: str, offset: float) -> np.ndarray:
    fig, axes = plt.subplots(2, 3, figsize=(7.2, 4.8), dpi=80, constrained_layout=True)
    for j, ax in enumerate(axes.flat):
        ax.plot(t, values[:, j], lw=1.2)
        ax.set_title(names[j], fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.4)
        ax.set_xlabel(BEAD_AXIS, fontsize=7)
        ax.set_ylabel(unit, fontsize=7)
        _job_axis(ax, offset, 6)
    fig.suptitle(title, fontsize=10)
    return _to_image(fig)


def plan_figures(plan: GluePlan) -> dict[str, np.ndarray]:
    """RGB images (H, W, 3) uint8 of the seed's four figures of the planned bead, keyed by :data:`FIGURES`."""
    bead = plan.bead
    names = list(bead.joint_names)
    offset = bead_window(plan)[0]
    out = {
        'joint position': _joint_figure(bead.times, bead.q, names, 'Desired joint position', 'rad', offset),
        'joint velocity': _joint_figure(bead.times, bead.qd, names, 'Desired joint velocity', 'rad/s', offset),
        'joint acceleration': _joint_figure(bead.times, bead.qdd, names, 'Desired joint acceleration', 'rad/s^2',
                                            offset),
    }
    fig, ax = plt.subplots(figsize=(7.2, 3.3), dpi=80, constrained_layout=True)
    ax.plot(bead.times, bead.tcp_speed, lw=1.2, label='planned')
    ax.axhline(plan.job.tcp_speed, color='k', lw=0.8, ls='--', label='commanded')
    ax.set(title='Desired end-effector (tip) linear speed', xlabel=BEAD_AXIS, ylabel='speed [m/s]')
    _job_axis(ax, offset, 8)
    ax.grid(True, lw=0.4)
    ax.legend(fontsize=8)
    out['tcp speed'] = _to_image(fig)
    return out


def speed_summary(plan: GluePlan, waited: float | None = None) -> str:
    """Markdown lines with the planned TCP speed figures and the plan's size; `waited` [s]: from the Plan click to
    the plan on the page (measuring the part, planning, the figures), the time the user waited."""
    s = plan.summary
    start, end = bead_window(plan)
    return (f'**Bead** {s.bead_length:.3f} m in {s.bead_duration:.2f} s (total {s.total_duration:.2f} s)  \n'
            f'**Time**: the slider spans the whole job, 0 to {s.total_duration:.2f} s; the figures show the bead, '
            f'{start:.2f} to {end:.2f} s of it (their lower axis from the bead start, upper axis the job time)  \n'
            f'**Planned TCP speed** mean {s.speed_mean:.4f}, min {s.speed_min:.4f}, max {s.speed_max:.4f} m/s '
            f'(commanded {plan.job.tcp_speed:.3f})  \n'
            f'**Within 1 %** on {100 * s.within_1pct:.1f} % of the bead; {s.slowdowns} slowdown(s); '
            f'peak joint speed {100 * s.max_velocity_usage:.0f} % of the limit  \n'
            + (f'ready {duration_text(waited)} after Plan was pressed (planning {duration_text(s.planning_seconds)} '
               f'of it)' if waited is not None else f'planned in {duration_text(s.planning_seconds)}'))


def duration_text(seconds: float) -> str:
    """A wait [s] as a user reads it: ms below a second, else seconds to 0.1 s."""
    return f'{1e3 * seconds:.0f} ms' if seconds < 1.0 else f'{seconds:.1f} s'

