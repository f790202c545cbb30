"""Off-screen picture of the arm over the windshield with tip paths drawn in (MuJoCo, MUJOCO_GL=egl).

The model comes from the shared robot description (URDF/MJCF generator), not from the simulator: the report
must also be made for runs on a real robot.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from ur_sim_driver.description.mjcf import add_static_mesh, build_mjcf
from ur_sim_driver.description.params import URParams, joint_names
from ur_sim_driver.description.tool import ToolDef

_MAX_SEGMENTS = 600  # per path, to stay within the renderer's geom budget


def scene_xml(robot: URParams, tool: ToolDef | None, meshes: Sequence[tuple[str, Path, np.ndarray]], width: int,
              height: int) -> str:
    """MJCF of the arm with its tool and static (visual-only) meshes, with an off-screen buffer of width x height."""
    xml = build_mjcf(robot, tool=tool)
    for name, stl, pose in meshes:
        xml = add_static_mesh(xml, name, stl, pose, collide=False)
    root = ET.fromstring(xml)
    visual = root.find('visual')
    if visual is None:
        visual = ET.SubElement(root, 'visual')
    ET.SubElement(visual, 'global', offwidth=str(width), offheight=str(height))
    return ET.tostring(root, encoding='unicode')


def _add_path(scene: mujoco.MjvScene, points: np.ndarray, rgba: Sequence[float], radius: float) -> None:
    step = max(1, len(points) // _MAX_SEGMENTS)
    pts = points[::step]
    for a, b in zip(pts[:-1], pts[1:]):
        if scene.ngeom >= scene.maxgeom:
            return
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.zeros(9),
                            np.asarray(rgba, dtype=np.float32))
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, radius, a, b)
        scene.ngeom += 1


def render_paths(robot: URParams, tool: ToolDef | None, q: np.ndarray, meshes: Sequence[tuple[str, Path, np.ndarray]],
                 paths: Sequence[tuple[np.ndarray, Sequence[float]]], out_png: Path, width: int = 960,
                 height: int = 720, lookat: Sequence[float] = (0.0, 0.5, 0.3), distance: float = 1.55,
                 azimuth: float = 130.0, elevation: float = -35.0, path_radius: float = 0.003) -> Path:
    """Render the arm at q (6,) [rad] with `paths` ((K, 3) world points [m], rgba) drawn as thin tubes.

    Returns:
        The PNG path written.
    """
    model = mujoco.MjModel.from_xml_string(scene_xml(robot, tool, meshes, width, height))
    data = mujoco.MjData(model)
    for name, value in zip(joint_names(), q):
        data.qpos[model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]] = value
    mujoco.mj_forward(model, data)
    camera = mujoco.MjvCamera()
    camera.lookat[:] = lookat
    camera.distance, camera.azimuth, camera.elevation = distance, azimuth, elevation
    with mujoco.Renderer(model, height, width, max_geom=4000) as renderer:
        renderer.update_scene(data, camera)
        for points, rgba in paths:
            _add_path(renderer.scene, np.asarray(points, dtype=float), rgba, path_radius)
        image = renderer.render()
    import matplotlib.pyplot as plt
    out_png = Path(out_png)
    out_png.parent.mkdir(parents=True, exist_ok=True)
    plt.imsave(out_png, image)
    return out_png
