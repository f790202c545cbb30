"""A video of the run: MuJoCo off-screen frames of the recorded joint states, the bead growing on the glass.

Frames at ``fps`` of robot time (the run as it happened, whatever the simulation's real-time factor), H.264
MP4 through imageio-ffmpeg (its wheel carries an ffmpeg binary), yuv420p so that browsers play it. The model is
the shared description's (URDF/MJCF generator), not the simulator's: a run on a real robot gets its video too.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import imageio_ffmpeg
import mujoco
import numpy as np

from ur_glue_planner.report.render import scene_xml
from ur_sim_driver.description.bead import Bead, draw_bead
from ur_sim_driver.description.params import URParams, joint_names
from ur_sim_driver.description.tool import ToolDef

_MAX_BEAD_SEGMENTS = 400  # geoms per frame for the bead (draw_bead thins the bead to the renderer's budget)
BEAD_RGBA = (0.95, 0.55, 0.1, 1.0)


def _progress(done: int, total: int, started: float) -> None:
    rate = done / max(time.perf_counter() - started, 1e-6)
    sys.stdout.write(f'\r  video: frame {done}/{total} ({100.0 * done / total:5.1f} %, {rate:4.1f} frames/s)')
    if done == total:
        sys.stdout.write('\n')
    sys.stdout.flush()


def add_bead(scene: mujoco.MjvScene, points: np.ndarray, widths: np.ndarray, heights: np.ndarray,
             times: np.ndarray, rgba: Sequence[float] = BEAD_RGBA) -> int:
    """Draw a bead (deposit points (N, 3) [m] in the world, widths, heights, times (N,)) with ur_sim's own
    ``draw_bead`` (capsules on the glass); returns the geoms added."""
    if len(points) < 2:
        return 0
    return draw_bead(scene, Bead(points, widths, heights, times), rgba)


def render_video(robot: URParams, tool: ToolDef | None, meshes, t: np.ndarray, q: np.ndarray, out_mp4: Path,
                 bead=None, bead_t0: float = 0.0, fps: int = 30, width: int = 640, height: int = 480,
                 lookat: Sequence[float] = (0.0, 0.6, 0.2), distance: float = 1.5, azimuth: float = -60.0,
                 elevation: float = -45.0, progress: Callable[[int, int, float], None] | None = _progress) -> dict:
    """Write the run as an MP4.

    Args:
        robot, tool, meshes: The scene (see render.scene_xml).
        t: (K,) [s] recorded joint state times, increasing; q: (K, 6) [rad].
        out_mp4: File to write.
        bead: The deposit (BeadPoints, robot time) or None; bead_t0: robot time [s] of t = 0.
        fps, width, height: Video frame rate and size.
        progress: Called as progress(frames done, total, start time) (None: silent).

    Returns:
        frames, duration [s], seconds of wall time it took, fps, size.
    """
    started = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(scene_xml(robot, tool, meshes, width, height))
    # software rendering (no GPU here): shadows and reflections cost 4x a frame; 2x multisampling keeps edges clean
    model.vis.quality.offsamples = 2
    model.vis.quality.numslices, model.vis.quality.numstacks = 12, 6  # capsules of the bead: 1/6 the triangles
    data = mujoco.MjData(model)
    adr = [model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)] for n in joint_names()]
    camera = mujoco.MjvCamera()
    camera.lookat[:] = lookat
    camera.distance, camera.azimuth, camera.elevation = distance, azimuth, elevation
    frames_t = np.arange(t[0], t[-1] + 1e-9, 1.0 / fps)
    total = len(frames_t)
    out_mp4 = Path(out_mp4)
    out_mp4.parent.mkdir(parents=True, exist_ok=True)
    writer = imageio_ffmpeg.write_frames(str(out_mp4), (width, height), fps=fps, codec='libx264',
                                         pix_fmt_out='yuv420p', quality=7, macro_block_size=16,
                                         output_params=['-movflags', '+faststart'])
    writer.send(None)
    try:
        with mujoco.Renderer(model, height, width, max_geom=model.ngeom + 100 + _MAX_BEAD_SEGMENTS) as renderer:
            for i, tf in enumerate(frames_t):
                for j, a in enumerate(adr):
                    data.qpos[a] = np.interp(tf, t, q[:, j])
                mujoco.mj_kinematics(model, data)
                renderer.update_scene(data, camera)
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
                if bead is not None:
                    now = bead.until(bead_t0 + tf)
                    add_bead(renderer.scene, now.points, now.widths, now.heights, now.times)
                writer.send(np.ascontiguousarray(renderer.render()))
                if progress is not None and (i % 15 == 14 or i == total - 1):
                    progress(i + 1, total, started)
    finally:
        writer.close()
    return {'frames': total, 'duration_s': float(frames_t[-1] - frames_t[0]) if total else 0.0,
            'render_seconds': time.perf_counter() - started, 'fps': fps, 'size': [width, height]}
