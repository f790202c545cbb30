"""Scene assembly for the simulator: arm + optional tool + optional static bodies, as one MJCF string."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from ur_sim_driver.description.params import rpy_to_matrix
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.paths import config_dir


def pose_matrix(xyz: list[float], rpy: list[float]) -> np.ndarray:
    """4x4 homogeneous transform from translation [m] and fixed-axis roll, pitch, yaw [rad] (URDF convention)."""
    t = np.eye(4)
    t[:3, :3] = rpy_to_matrix(rpy)
    t[:3, 3] = xyz
    return t


def load_scene(name: str) -> list[tuple[str, Path, np.ndarray, bool]]:
    """Static bodies of scene `name` from config/scenes/<name>.yaml: (body name, STL path, 4x4 pose, collide) each.

    A body's optional `collide` key (default true) set to false makes it visual only.

    Raises:
        ConfigError: unknown scene (lists the choices), a missing mesh file or a non-boolean `collide`.
    """
    scenes = config_dir() / 'scenes'
    choices = sorted(p.stem for p in scenes.glob('*.yaml'))
    path = scenes / f'{name}.yaml'
    if not path.is_file():
        raise ConfigError(f"scene '{name}' is unknown; valid choices: {', '.join(['empty', *choices])}")
    spec = yaml.safe_load(path.read_text()) or {}
    bodies = []
    for body in spec.get('bodies', []):
        mesh = (config_dir().parent / body['mesh']).resolve()
        if not mesh.is_file():
            raise ConfigError(f"scene '{name}': mesh '{body['mesh']}' of body '{body['name']}' not found at {mesh}")
        collide = body.get('collide', True)
        if not isinstance(collide, bool):
            raise ConfigError(f"scene '{name}': 'collide' of body '{body['name']}' must be true or false, "
                              f'got {collide!r}')
        bodies.append((body['name'], mesh, pose_matrix(body['pose']['xyz'], body['pose']['rpy']), collide))
    return bodies
