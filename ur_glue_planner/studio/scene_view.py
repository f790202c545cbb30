"""Drawing in the viser scene: a robot (one frame per link carrying its meshes), waypoint markers, line paths."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import viser

from ur_common.quaternions import matrix_from_quat, quat_from_matrix
from ur_glue_planner.studio.robot_geometry import RobotModel

GREEN = (40, 190, 70)
RED = (225, 40, 40)
GREY = (150, 150, 150)
SELECTED = (255, 200, 0)
MARKER_RADIUS = 0.008  # [m]


def wxyz(rotation: np.ndarray) -> np.ndarray:
    """Quaternion (w, x, y, z) of a rotation (3, 3)."""
    return quat_from_matrix(np.asarray(rotation, dtype=float))


class RobotView:
    """A robot in the scene under ``root``: link frames moved by :meth:`show`, meshes fixed to them."""

    def __init__(self, server: viser.ViserServer, root: str, robot: RobotModel, opacity: float | None = None,
                 tint: Sequence[int] | None = None) -> None:
        self.server = server
        self.root = root
        self.robot = robot
        self.frames = {}
        for link in robot.links:
            self.frames[link] = server.scene.add_frame(f'{root}/{link}', show_axes=False)
        for k, shape in enumerate(robot.shapes):
            color = tuple(tint) if tint is not None else shape.color
            server.scene.add_mesh_simple(f'{root}/{shape.link}/shape_{k}', shape.mesh.vertices, shape.mesh.faces,
                                         color=color, opacity=opacity, cast_shadow=False, receive_shadow=False)

    def show(self, names: Sequence[str], q: Sequence[float]) -> None:
        """Put the links at joint positions ``q`` (by joint ``names``)."""
        poses = self.robot.link_poses(names, q)
        with self.server.atomic():
            for link, pose in poses.items():
                frame = self.frames.get(link)
                if frame is not None:
                    frame.position = pose[:3, 3]
                    frame.wxyz = wxyz(pose[:3, :3])

    def set_visible(self, visible: bool) -> None:
        for frame in self.frames.values():
            frame.visible = visible

    def remove(self) -> None:
        """Take the robot out of the scene (a frame's removal takes its meshes along)."""
        for frame in self.frames.values():
            frame.remove()
        self.frames = {}


def polyline_segments(points: np.ndarray) -> np.ndarray:
    """Consecutive points (K, 3) as segments (K - 1, 2, 3)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.stack([p[:-1], p[1:]], axis=1)


def pose_to_wxyz_xyz(pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(wxyz, position) of a pose (4, 4)."""
    return wxyz(pose[:3, :3]), np.asarray(pose[:3, 3], dtype=float)


def rotation_of(wxyz_value: Sequence[float]) -> np.ndarray:
    """Rotation (3, 3) of a (w, x, y, z) quaternion."""
    return matrix_from_quat(np.asarray(wxyz_value, dtype=float))
