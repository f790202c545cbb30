"""Plots in the style of the seeds' MATLAB figures: one subplot per joint, written as PNG files."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use('Agg')  # headless: files only
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_joints(t: np.ndarray, series: dict[str, np.ndarray], names: Sequence[str], title: str, ylabel: str,
                path: Path) -> Path:
    """Plot (K, n) series against t (K,) [s]: a 2x3 grid, one subplot per joint, one line per series.

    Args:
        t: times (K,) [s].
        series: label -> (K, n) values; several labels overlay (e.g. planned and measured).
        names: n joint names (subplot titles).
        title: figure title.
        ylabel: y axis label with unit.
        path: PNG file to write.
    """
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), constrained_layout=True)
    for j, ax in enumerate(axes.flat[:len(names)]):
        for label, values in series.items():
            ax.plot(t if len(t) == len(values) else np.arange(len(values)), np.asarray(values)[:, j], label=label)
        ax.set_title(names[j])
        ax.set_xlabel('time [s]')
        ax.set_ylabel(ylabel)
        ax.grid(True)
    if len(series) > 1:
        axes.flat[0].legend()
    fig.suptitle(title)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def plot_joint_states(t: np.ndarray, q: np.ndarray, qd: np.ndarray, names: Sequence[str], out_dir: Path,
                      stem: str, title: str) -> list[Path]:
    """The seed 2 pair of figures: joint positions and joint velocities over time."""
    out_dir = Path(out_dir)
    return [plot_joints(t, {'position': q}, names, f'{title}: joint positions', 'position [rad]',
                        out_dir / f'{stem}_positions.png'),
            plot_joints(t, {'velocity': qd}, names, f'{title}: joint velocities', 'velocity [rad/s]',
                        out_dir / f'{stem}_velocities.png')]
