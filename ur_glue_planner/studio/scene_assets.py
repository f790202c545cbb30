"""Files of the job's scene: the glass mesh and its convex collision pieces, placed at the job's windshield pose."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ur_common.paths import package_dir
from ur_glue_planner.job import WindshieldSpec
from ur_sim_driver.description.scene import load_scene, pose_matrix


def glass_pose(spec: WindshieldSpec) -> np.ndarray:
    """World-from-local pose (4, 4) of the job's glass."""
    return pose_matrix(list(spec.xyz), list(spec.rpy))


def glass_mesh_path(spec: WindshieldSpec) -> Path:
    """The job's glass mesh (STL, local frame [m]); relative paths are relative to the package directory."""
    path = Path(spec.mesh)
    return path if path.is_absolute() else package_dir() / path


def glass_pieces(spec: WindshieldSpec) -> list[tuple[Path, np.ndarray]]:
    """(STL, world pose (4, 4)) of the windshield's convex collision pieces (config/scenes/windshield.yaml), stored
    in the glass's local frame like the whole mesh, so they take the job's pose."""
    pose = glass_pose(spec)
    return [(mesh, pose) for _, mesh, _, collide in load_scene('windshield') if collide]
