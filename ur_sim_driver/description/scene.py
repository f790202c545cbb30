"""Scenes: the static bodies around the arm (meshes and poses) and the part scanners over them, from a scene file."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from ur_common.paths import config_dir
from ur_sim_driver.description.params import rpy_to_matrix
from ur_sim_driver.description.part_scan import ScannerSetup, parse_scanners
from ur_sim_driver.errors import ConfigError


def pose_matrix(xyz: list[float], rpy: list[float]) -> np.ndarray:
    """4x4 homogeneous transform from translation [m] and fixed-axis roll, pitch, yaw [rad] (URDF convention)."""
    t = np.eye(4)
    t[:3, :3] = rpy_to_matrix(rpy)
    t[:3, 3] = xyz
    return t


def scene_file(name: str) -> Path:
    """The scene file of ``name``: a scene in config/scenes (``windshield``) or a path to a ``.yaml`` scene file.

    Raises:
        ConfigError: neither (lists the named scenes).
    """
    scenes = config_dir() / 'scenes'
    path = scenes / f'{name}.yaml'
    if path.is_file():
        return path
    if str(name).endswith(('.yaml', '.yml')) and Path(name).is_file():
        return Path(name).resolve()
    choices = sorted(p.stem for p in scenes.glob('*.yaml'))
    raise ConfigError(f"scene '{name}' is unknown; valid choices: {', '.join(['empty', *choices])} or the path "
                      'of a scene .yaml file')


def read_scene(name: str) -> tuple[list[tuple[str, Path, np.ndarray, bool]], ScannerSetup | None]:
    """Static bodies of scene ``name`` ((body name, STL path, 4x4 pose, collide) each) and its part scanners.

    A body's optional `collide` key (default true) set to false makes it visual only. Mesh paths of a named
    scene are relative to the package root; those of a scene file relative to the file's folder.

    Raises:
        ConfigError: unknown scene (lists the choices), a missing mesh file, a non-boolean `collide`, an invalid
            `scanners` block or scanners aimed at bodies the scene does not have.
    """
    path = scene_file(name)
    root = config_dir().parent if path.parent == config_dir() / 'scenes' else path.parent
    spec = yaml.safe_load(path.read_text()) or {}
    bodies = []
    for body in spec.get('bodies', []):
        mesh = (root / body['mesh']).resolve()
        if not mesh.is_file():
            raise ConfigError(f"scene '{name}': mesh '{body['mesh']}' of body '{body['name']}' not found at {mesh}")
        collide = body.get('collide', True)
        if not isinstance(collide, bool):
            raise ConfigError(f"scene '{name}': 'collide' of body '{body['name']}' must be true or false, "
                              f'got {collide!r}')
        bodies.append((body['name'], mesh, pose_matrix(body['pose']['xyz'], body['pose']['rpy']), collide))
    scanners = None
    if spec.get('scanners') is not None:
        scanners = parse_scanners(spec['scanners'], f"scene '{name}': scanners")
        missing = sorted(set(scanners.targets) - {b[0] for b in bodies})
        if missing:
            raise ConfigError(f"scene '{name}': scanners.targets names bodies the scene does not have: "
                              f"{', '.join(missing)}; bodies: {', '.join(b[0] for b in bodies)}")
    return bodies, scanners


def load_scene(name: str) -> list[tuple[str, Path, np.ndarray, bool]]:
    """Static bodies of scene ``name``: (body name, STL path, 4x4 pose, collide) each (see :func:`read_scene`)."""
    return read_scene(name)[0]
