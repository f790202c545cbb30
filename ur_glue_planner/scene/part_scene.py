"""A generated part as a scene file for ur_sim (``scene:=<folder>/scene.yaml``): its glass and the cell around it.

The part's glass is written as the nominal one is (``meshes/windshield.stl`` and its convex collision pieces, 24
or more for a bent part, in the glass's own frame) into the part's folder, placed at the part's true pose;
everything else of the cell (the part scanners) is copied from the nominal scene, ``config/scenes/windshield.yaml``.
Mesh paths are relative to the scene file, so the folder can be moved or shared.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from ur_common.paths import config_dir
from ur_glue_planner.scene.part_variation import Part
from ur_glue_planner.scene.windshield import write_stl
from ur_glue_planner.scene.windshield_pieces import piece_name, write_pieces

NOMINAL_SCENE = 'windshield'


def pose_xyz_rpy(pose: np.ndarray) -> dict:
    """A 4x4 pose as a scene file writes it: xyz [m] and URDF roll, pitch, yaw [rad] (fixed axes x, y, z)."""
    rpy = Rotation.from_matrix(pose[:3, :3]).as_euler('xyz')
    return {'xyz': [float(x) for x in pose[:3, 3]], 'rpy': [float(x) for x in rpy]}


GRIDS = ((12, 2), (16, 3), (24, 4), (32, 6))  # (u, v) tiles tried in turn: a bent part may need finer ones


def _collision_pieces(folder: Path, part: Part) -> list[Path]:
    """The glass's convex collision pieces on the coarsest grid whose hulls stay within the pieces' limit of the
    glass (0.5 mm): the nominal glass's 12 x 2, finer for a bent part."""
    for n_u, n_v in GRIDS[:-1]:
        try:
            return write_pieces(folder, part.model, n_u, n_v)
        except ValueError:
            continue
    return write_pieces(folder, part.model, *GRIDS[-1])


def write_part_scene(part: Part, folder: str | Path, template: str = NOMINAL_SCENE) -> Path:
    """Write ``folder``/scene.yaml with the part's meshes beside it; returns the scene file's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_stl(folder / 'windshield.stl', part.model, frame='local')
    pieces = _collision_pieces(folder, part)
    pose = pose_xyz_rpy(part.model.pose)
    spec = yaml.safe_load((config_dir() / 'scenes' / f'{template}.yaml').read_text())
    spec['bodies'] = [{'name': 'windshield', 'mesh': 'windshield.stl', 'collide': False, 'pose': pose}] + [
        {'name': piece_name(i), 'mesh': p.name, 'pose': pose} for i, p in enumerate(pieces)]
    text = (f'# Part {part.index} of seed {part.seed} (ur_glue_planner.scene.part_variation): '
            f'{part.describe()}\n' + yaml.safe_dump(spec, default_flow_style=None, sort_keys=False, width=120))
    path = folder / 'scene.yaml'
    path.write_text(text)
    return path
