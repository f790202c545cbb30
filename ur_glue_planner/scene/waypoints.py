"""Bead waypoints and tip orientations of a job: the listed points, or the glass outline.

- ``waypoints``: the job's points (seed 1's clicks lie on the glass), moved ``standoff`` along
  the glass normal, with the job's orientation(s).
- ``auto``: points ``inset`` inside the glass edge on the glue face, every ``point_spacing``,
  ``standoff`` above it. The tool axis makes the angle ``tilt`` with the surface normal,
  leaning towards the robot base (the seed's fixed orientation leans ~18 deg that way, which
  keeps the wrist within reach of the far edge); the roll about the tool axis is the smallest
  rotation away from the job's reference orientation, so it never winds up along a loop.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.spatial.transform import Rotation

from ur_glue_planner.errors import JobError
from ur_glue_planner.job import GlueJob, WindshieldSpec
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.scene.part_variation import move_onto
from ur_glue_planner.scene.registration import Registration
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD, WindshieldModel
from ur_sim_driver.description.params import rpy_to_matrix
from ur_sim_driver.description.tool import ToolDef, get_tool


def windshield_model(spec: WindshieldSpec) -> WindshieldModel:
    """The project's glass model placed at the job's pose."""
    pose = np.eye(4)
    pose[:3, :3] = rpy_to_matrix(spec.rpy)
    pose[:3, 3] = spec.xyz
    return dataclasses.replace(DEFAULT_WINDSHIELD, world_from_local=tuple(tuple(r) for r in pose.tolist()))


def tool_axis(tool: ToolDef | str | None) -> np.ndarray:
    """Unit tool axis (3,) in the tip frame: tool0's z (out of the flange) seen from the tip.

    For the dispenser this is the tip frame's +y: the nozzle points along it. ``tool``: the tool or its name.
    """
    tool_def = get_tool(tool) if tool is None or isinstance(tool, str) else tool
    if tool_def is None:
        return np.array([0.0, 0.0, 1.0])
    return tool_def.tip_in_tool0()[:3, :3].T @ np.array([0.0, 0.0, 1.0])


def align_axis(reference: np.ndarray, axis: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Rotation(s) (..., 3, 3): the smallest turn of ``reference`` (3, 3) that points its local
    ``axis`` (3,) along the world ``direction`` (..., 3) (unit)."""
    a = reference @ axis
    d = np.asarray(direction, dtype=float)
    v = np.cross(a, d)
    c = d @ a
    if np.any(c <= -1.0 + 1e-9):
        raise ValueError("direction opposite to the reference tool axis: the turn is not unique")
    sine = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = np.arctan2(sine, c[..., None])
    turn = Rotation.from_rotvec(v * (angle / np.where(sine > 0.0, sine, 1.0)))  # about a x d, by the angle between
    return turn.as_matrix() @ reference


def auto_waypoints(model: WindshieldModel, inset: float, spacing: float, tilt: float, standoff: float,
                   reference: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints (K, 3) [m] and tip rotations (K, 3, 3) along the inset glass outline.

    Args:
        model: Glass model (world placement included).
        inset: Distance inside the glass edge [m].
        spacing: Distance between points [m].
        tilt: Tool axis to normal [rad], leaning towards the robot base (world z axis).
        standoff: Tip height above the glue face [m].
        reference: Rotation (3, 3) whose roll about the tool axis is kept.
        axis: Tool axis (3,) in the tip frame.
    """
    try:
        glass = model.glass.inset(inset)
    except ValueError as exc:
        raise JobError(f"path.inset: {inset} m does not fit the glass: {exc}") from exc
    n = max(8, math.ceil(glass.length / spacing))
    uv = glass.sample(n)
    normal = model.surface_normal(uv[:, 0], uv[:, 1])
    points = model.surface_point(uv[:, 0], uv[:, 1]) + standoff * normal
    lean = -points * np.array([1.0, 1.0, 0.0])  # horizontal, towards the base's z axis
    lean -= np.sum(lean * normal, axis=1, keepdims=True) * normal
    norm = np.linalg.norm(lean, axis=1, keepdims=True)
    lean = np.where(norm > 1e-9, lean / np.where(norm > 1e-9, norm, 1.0), 0.0)
    body = math.cos(tilt) * normal + math.sin(tilt) * lean  # from the tip up into the tool
    body /= np.linalg.norm(body, axis=1, keepdims=True)
    return points, align_axis(reference, axis, -body)


def job_waypoints(job: GlueJob, axis: np.ndarray | None = None, part: Registration | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Bead waypoints (K, 3) [m] and tip rotations (K, 3, 3) of a job, world frame; ``axis``: the tool's
    (:func:`tool_axis`; None: found from ``job.tool``). With ``part`` (the part as measured) they move with the
    glass: each point to the same place on the measured glass, each rotation turned with the part."""
    model = windshield_model(job.windshield)
    zyx = np.array(job.path.orientation_zyx)
    rots = np.array([rotation_from_zyx_euler(*e) for e in zyx])
    if job.path.source == "auto":
        points, rots = auto_waypoints(model, job.path.inset, job.path.point_spacing,
                                      math.radians(job.path.tilt_deg), job.standoff, rots[0],
                                      tool_axis(job.tool) if axis is None else axis)
    else:
        points = np.array(job.path.waypoints)
        if len(rots) == 1:
            rots = np.repeat(rots, len(points), axis=0)
        if job.standoff > 0.0:
            _, _, normal = model.project(points)
            points = points + job.standoff * normal
    if part is None:
        return points, rots
    return move_onto(points, model, part.model), part.transform[:3, :3] @ rots
