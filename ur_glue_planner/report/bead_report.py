"""The bead section of the report: the simulated bead against the plan's intended line, and its figure.

The intended line is the plan's tip line projected onto the glass (with a standoff the tip runs above it).
The standoff along the bead is the distance from the nozzle tip to each deposit point along the nozzle axis,
the tip posed by the joint states recorded when that point was laid. The nominal width is that of the bead's
section (triangular, ur_sim's dispenser model) of area flow / commanded speed.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ur_glue_planner.motion.plan import GluePlan  # noqa: E402
from ur_glue_planner.report.bead_metrics import StationProfile, bead_quality, project_onto_polyline  # noqa: E402
from ur_glue_planner.scene.waypoints import tool_axis, windshield_model  # noqa: E402
from ur_sim_driver.description.bead import section  # noqa: E402

LABELS = {'constant_speed': 'our planner (constant speed, blended corners, flying start)',
          'seed1': "seed 1's method (per-segment time, min-jerk spline, no blending)"}


def nominal_width(plan: GluePlan) -> float:
    """Width [m] of the bead laid at the job's flow rate and commanded speed."""
    area = plan.job.dispenser.flow_rate * 1e-6 / plan.job.tcp_speed
    return float(section(area)[0])


def standoffs(plan: GluePlan, run, times: np.ndarray, points: np.ndarray) -> np.ndarray | None:
    """Tip-to-deposit distance [m] along the nozzle axis at each deposit (N,), from the recorded joint states."""
    whole = getattr(run, 'whole', None)
    if whole is None or run.whole_t0 is None or len(whole.t) < 2:
        return None
    t = times - run.whole_t0
    q = np.column_stack([np.interp(t, whole.t, whole.q[:, j]) for j in range(whole.q.shape[1])])
    axis = tool_axis(plan.tool)
    out = np.empty(len(points))
    for k, qk in enumerate(q):
        pose = plan.kinematics.fk(qk)
        out[k] = float((points[k] - pose[:3, 3]) @ (pose[:3, :3] @ axis))
    return out


def analyse_bead(plan: GluePlan, run, intended: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> tuple[dict, StationProfile] | None:
    """summary.json's ``bead`` figures and the station profile, or None when no bead was collected.

    ``intended``: the line (P, 3) and corner points (K, 3) [m] the bead is judged against, when they are not the
    plan's own (a part the plan did not know exactly: the line as it lies on the real glass).
    """
    dep = getattr(run, 'deposit', None) if run is not None else None
    if dep is None or len(dep.times) == 0:
        return None
    if intended is None:
        model = plan.surface if plan.surface is not None else windshield_model(plan.job.windshield)
        line, corner_points = model.project(plan.line)[1], model.project(plan.waypoints)[1]
    else:
        line, corner_points = intended
    corners = project_onto_polyline(corner_points, line)[0]
    figures, prof = bead_quality(dep.points, dep.widths, dep.heights, dep.times, line, nominal_width(plan),
                                 plan.job.path.closed, corner_stations=corners,
                                 standoff=standoffs(plan, run, dep.times, dep.points))
    figures['nominal_area_mm2'] = plan.dispense.nominal_area
    figures['method'] = plan.method
    return figures, prof


def plot_bead(axes, prof: StationProfile, figures: dict, title: str) -> None:
    """Width along the line (top axis) and the centre's lateral deviation (bottom axis)."""
    ax_w, ax_l = axes
    nominal, band = figures['nominal_width_mm'], figures['band']
    x = prof.station
    ax_w.axhspan(nominal * (1 - band), nominal * (1 + band), color='tab:green', alpha=0.15, label='nominal +-5 %')
    ax_w.axhline(nominal, color='tab:green', lw=0.8)
    ax_w.plot(x, 1e3 * prof.width, lw=0.9, color='tab:blue', label='bead width')
    for gap in figures.get('gaps', []):
        ax_w.axvspan(gap['station_mm'] * 1e-3, (gap['station_mm'] + gap['length_mm']) * 1e-3, color='red',
                     alpha=0.3)
    for blob in figures.get('blobs', []):
        ax_w.annotate(blob['where'], (blob['station_mm'] * 1e-3, blob['peak_width_mm']), fontsize=7,
                      color='tab:red')
    ax_w.set(title=title, xlabel='station along the bead [m]', ylabel='width [mm]')
    top = max(2.0 * nominal, float(1e3 * prof.width.max()) * 1.05 if len(prof.width) else 0.0)
    ax_w.set_ylim(0.0, min(top, 4.0 * nominal))
    ax_w.grid(True)
    ax_w.legend(fontsize=7, loc='lower right')
    ax_l.plot(prof.point_station, 1e3 * prof.point_lateral, ',', color='tab:purple')
    ax_l.axhline(0.5, color='k', lw=0.8, ls='--', label='0.5 mm')
    ax_l.set(xlabel='station along the bead [m]', ylabel='bead centre to line [mm]')
    ax_l.grid(True)
    ax_l.legend(fontsize=7, loc='upper right')
    if 'width_mm' not in figures:
        ax_w.text(0.01, 0.02, f"no bead on the line ({figures['deposit_points']} deposit points)",
                  transform=ax_w.transAxes, fontsize=7, va='bottom')
        return
    w, lat = figures['width_mm'], figures['lateral_deviation_mm']
    closure = figures.get('closure', {}).get('overlap_mm')
    text = (f"width {w['mean']:.2f} mm (min {w['min']:.2f}, max {w['max']:.2f}); within +-5 %: "
            f"{100 * figures['width_within_band_fraction']:.1f} % of the length\n"
            f"gaps {figures['gap_length_mm']:.1f} mm; blobs {len(figures['blobs'])}; lateral max {lat['max']:.2f} mm"
            + (f"; closure overlap {closure:+.1f} mm" if closure is not None else ''))
    ax_w.text(0.01, 0.02, text, transform=ax_w.transAxes, fontsize=7, va='bottom')


def write_bead_figure(results: list[tuple[str, StationProfile, dict]], path: Path) -> Path:
    """One column per method (label, profile, figures), side by side, as a PNG."""
    fig, axes = plt.subplots(2, len(results), figsize=(7 * len(results), 6.5), constrained_layout=True,
                             squeeze=False)
    for col, (label, prof, figures) in enumerate(results):
        plot_bead(axes[:, col], prof, figures, label)
    fig.suptitle('Glue bead on the glass: width and placement along the bead')
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
