"""The glue job report: the seed's four figures, planned against executed paths and joints, a rendered
picture, and summary.json. Executed values come from the joint states recorded during the run."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ur_glue_planner.motion.plan import GluePlan  # noqa: E402
from ur_glue_planner.report.metrics import point_to_polyline_distance, speed_stats, tracking_error  # noqa: E402
from ur_glue_planner.report.plots import plot_joints  # noqa: E402


@dataclass(frozen=True, eq=False)
class Executed:
    """Joint states recorded during the bead, on the bead's clock.

    Attributes:
        t: (K,) [s] from the bead start. q: (K, n) [rad]. qd: (K, n) [rad/s].
        whole: The whole run's joint states (a Recording, t from ``whole_t0``), for the video.
        start_stamp: Robot time [s] of the bead's trajectory start. whole_t0: robot time [s] of whole.t = 0.
        switches: The dispenser's set_io calls (SwitchRecord). deposit: The simulated bead (BeadPoints) or None.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    whole: object = None
    start_stamp: float | None = None
    switches: tuple = ()
    deposit: object = None
    whole_t0: float | None = None


def executed_tip(plan: GluePlan, run: Executed) -> tuple[np.ndarray, np.ndarray]:
    """Tip positions (K, 3) [m] and speeds (K,) [m/s] of the recorded joint states (FK and J qd)."""
    kin = plan.kinematics
    pos = np.empty((len(run.t), 3))
    speed = np.empty(len(run.t))
    for k, (q, qd) in enumerate(zip(run.q, run.qd)):
        pose = kin.fk(q)
        pos[k] = pose[:3, 3]
        speed[k] = np.linalg.norm(kin.jacobian(q)[:3] @ qd)
    return pos, speed


def _cruise(t: np.ndarray, plan: GluePlan) -> np.ndarray:
    ramp = plan.job.ramp_time
    return (t >= ramp) & (t <= plan.bead.times[-1] - ramp)


def summarize(plan: GluePlan, run: Executed | None, result_code: int | None, result_text: str) -> dict:
    """summary.json content: bead length and duration, planned and executed speed statistics, path deviation,
    tracking error and the result."""
    bead, v = plan.bead, plan.job.tcp_speed
    planned = speed_stats(bead.tip_pos, bead.tcp_speed, v, _cruise(bead.times, plan))
    summary = {
        'job': plan.job.source_file, 'ur_type': plan.job.ur_type, 'tool': plan.job.tool,
        'bead_length_m': float(plan.path.length), 'bead_duration_s': float(bead.times[-1]),
        'commanded_tcp_speed_m_s': v,
        'planned': {'tcp_speed_m_s': {k: planned[k] for k in ('mean', 'min', 'max')},
                    'fraction_within_1pct': planned['fraction_within_band'],
                    'slowdowns': len(bead.slowdowns), 'ik_seconds': bead.ik_seconds,
                    'planning_seconds': plan.summary.planning_seconds},
        'result': {'error_code': result_code, 'error_string': result_text},
        'method': plan.method,
        'dispenser': dispenser_summary(plan, run),
    }
    from ur_glue_planner.report.bead_report import analyse_bead
    bead_fig = analyse_bead(plan, run)
    if bead_fig is not None:
        summary['bead'] = bead_fig[0]
    inside = (run.t >= 0.0) & (run.t <= bead.times[-1]) if run is not None else np.zeros(0, bool)
    if run is not None and (inside.sum() < 2 or not _cruise(run.t[inside], plan).any()):
        # A client that could not keep up with /joint_states (a loaded machine, a fast simulation) has too few
        # samples of the bead to judge it: said so, instead of figures of nothing.
        summary['executed'] = {'samples': int(inside.sum()),
                               'note': 'too few joint states recorded during the bead to judge its execution'}
    elif run is not None:
        pos, speed = executed_tip(plan, Executed(run.t[inside], run.q[inside], run.qd[inside]))
        executed = speed_stats(pos, speed, v, _cruise(run.t[inside], plan))
        deviation = point_to_polyline_distance(pos, bead.tip_pos)
        summary['executed'] = {
            'samples': int(inside.sum()),
            'tcp_speed_m_s': {k: executed[k] for k in ('mean', 'min', 'max')},
            'fraction_within_1pct': executed['fraction_within_band'],
            'max_tip_deviation_mm': float(deviation.max() * 1e3),
            'max_joint_tracking_error_rad': float(tracking_error(run.t, run.q, bead.times, bead.q).max()),
        }
    return summary


def dispenser_summary(plan: GluePlan, run: Executed | None) -> dict:
    """The planned switching (bead trajectory time [s]) and, after a run, when each set_io call was made."""
    d = plan.dispense
    out = {'pin': d.pin, 'output': plan.job.dispenser.kind, 'flow_rate_ml_s': plan.job.dispenser.flow_rate,
           'on_delay_s': plan.job.dispenser.on_delay, 'off_delay_s': plan.job.dispenser.off_delay,
           'time_constant_s': plan.job.dispenser.time_constant, 'flying_start': plan.run_up > 0.0,
           'run_up_m': plan.run_up, **{k: v for k, v in d.as_dict().items() if k not in ('pin', 'flow_rate')}}
    calls, applied = [], []
    planned = {True: d.t_on, False: d.t_off}
    for r in (run.switches if run is not None else ()):
        if hasattr(r, 'event'):
            calls.append({'what': r.event.what, 'planned_t_s': r.event.t, 'called_at_t_s': r.trajectory_time,
                          'error_ms': 1e3 * (r.trajectory_time - r.event.t), 'robot_time_s': r.robot_time,
                          'success': r.success})
        elif r.trajectory_time is not None:
            applied.append({'state': r.state, 'planned_t_s': planned[r.state], 'seen_at_t_s': r.trajectory_time,
                            'error_ms': 1e3 * (r.trajectory_time - planned[r.state]), 'robot_time_s': r.robot_time})
    out['calls'] = calls
    out['applied'] = applied  # when the robot's io_states showed the output change
    return out


def write_report(plan: GluePlan, run: Executed | None, result_code: int | None, result_text: str,
                 out_dir: Path, render: bool = True) -> dict:
    """Write every figure and summary.json into out_dir; return the summary."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    bead = plan.bead
    names = list(bead.joint_names)
    plot_joints(bead.times, {'planned': bead.q}, names, 'Desired joint position', 'angle [rad]',
                out / 'joint_position.png')
    plot_joints(bead.times, {'planned': bead.qd}, names, 'Desired joint velocity', 'velocity [rad/s]',
                out / 'joint_velocity.png')
    plot_joints(bead.times, {'planned': bead.qdd}, names, 'Desired joint acceleration', 'acceleration [rad/s^2]',
                out / 'joint_acceleration.png')
    exec_pos = None
    fig, ax = plt.subplots(figsize=(9, 4), constrained_layout=True)
    ax.plot(bead.times, bead.tcp_speed, label='planned')
    if run is not None and len(run.t) > 1:
        inside = (run.t >= 0.0) & (run.t <= bead.times[-1])
        exec_pos, exec_speed = executed_tip(plan, Executed(run.t[inside], run.q[inside], run.qd[inside]))
        ax.plot(run.t[inside], exec_speed, label='executed', alpha=0.8)
        plot_joints(bead.times, {'planned': bead.q}, names, 'Planned and measured joint positions', 'angle [rad]',
                    out / 'joint_position_planned_vs_measured.png')
        _overlay_measured(out / 'joint_position_planned_vs_measured.png', bead, run, names)
    ax.axhline(plan.job.tcp_speed, color='k', lw=0.8, ls='--', label='commanded')
    ax.set(title='End-effector (tip) linear speed', xlabel='time [s]', ylabel='speed [m/s]')
    ax.grid(True)
    ax.legend()
    fig.savefig(out / 'tcp_speed.png', dpi=90)
    plt.close(fig)
    _plot_paths_3d(plan, exec_pos, out / 'tip_path_3d.png')
    if render:
        _render(plan, exec_pos, out / 'render.png')
    dep = getattr(run, 'deposit', None) if run is not None else None
    if dep is not None:
        np.savez_compressed(out / 'bead.npz', points=dep.points, widths=dep.widths, heights=dep.heights,
                            times=dep.times, line=plan.line)
    summary = summarize(plan, run, result_code, result_text)
    (out / 'summary.json').write_text(json.dumps(summary, indent=2))
    return summary


def _overlay_measured(path: Path, bead, run: Executed, names) -> None:
    # Re-draw with both series (plot_joints overlays series sampled on their own time bases).
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), constrained_layout=True)
    for j, ax in enumerate(axes.flat):
        ax.plot(bead.times, bead.q[:, j], label='planned')
        ax.plot(run.t, run.q[:, j], '--', label='measured')
        ax.set(title=names[j], xlabel='time [s]', ylabel='angle [rad]')
        ax.grid(True)
    axes.flat[0].legend()
    fig.suptitle('Bead: planned and measured joint positions')
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _plot_paths_3d(plan: GluePlan, executed: np.ndarray | None, path: Path) -> None:
    fig = plt.figure(figsize=(8, 6), constrained_layout=True)
    ax = fig.add_subplot(projection='3d')
    ax.plot(*plan.bead.tip_pos.T, label='planned tip path')
    if executed is not None:
        ax.plot(*executed.T, '--', label='executed tip path')
    ax.scatter(*plan.waypoints.T, s=12, c='k', label='waypoints')
    ax.set(xlabel='x [m]', ylabel='y [m]', zlabel='z [m]', title='Tip path on the windshield')
    ax.legend()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def scene_meshes(plan: GluePlan) -> list:
    """The job's static meshes for renders: [(name, STL path, world pose (4, 4))]."""
    from ur_sim_driver.description.scene import config_dir, pose_matrix
    spec = plan.job.windshield
    mesh = Path(spec.mesh) if Path(spec.mesh).is_absolute() else config_dir().parent / spec.mesh
    return [('windshield', mesh, pose_matrix(spec.xyz, spec.rpy))]


def _render(plan: GluePlan, executed: np.ndarray | None, path: Path) -> None:
    from ur_glue_planner.report.render import render_paths
    meshes = scene_meshes(plan)
    paths = [(plan.bead.tip_pos, (0.1, 0.3, 1.0, 1.0))]
    if executed is not None:
        paths.append((executed, (1.0, 0.1, 0.1, 1.0)))
    q = plan.bead.q[len(plan.bead.q) // 3]
    render_paths(plan.robot, plan.tool, q, meshes, paths, path)
