"""A robot to draw in the browser: triangle meshes per link (in the link frame) and link poses from a URDF.

Kinematics always come from the URDF (Pinocchio), the same one the planner uses or the one a running robot publishes
on ``robot_description``. Shapes: for our UR types, the simulator's own link shapes (capsules and cylinders of the
MJCF generator, with the tool), so the studio shows what ur_sim simulates; for any other URDF, its ``<visual>``
primitives (box, cylinder, sphere) where it has them, else a stick figure (a rod from each link to its children).
"""
from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin
import trimesh

from ur_sim_driver.description.mjcf import build_mjcf
from ur_sim_driver.description.params import UR_TYPES, Origin, URParams, load_ur_params
from ur_sim_driver.description.tool import TOOL_CHOICES, ToolDef, get_tool

LINK_COLOR = (150, 160, 175)
TOOL_COLOR = (230, 125, 25)
STICK_RADIUS = 0.02  # [m]


@dataclass(frozen=True, eq=False)
class LinkShape:
    """One mesh fixed to a link: ``mesh`` in the link frame [m], ``color`` RGB 0..255."""

    link: str
    mesh: trimesh.Trimesh
    color: tuple[int, int, int]


def _geom_mesh(kind: int, size: np.ndarray) -> trimesh.Trimesh | None:
    if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2.0 * size[1], radius=size[0], count=[12, 12])
    if kind == mujoco.mjtGeom.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2.0 * size[1], sections=24)
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return trimesh.creation.box(extents=2.0 * size[:3])
    return None


def ur_shapes(robot: URParams, tool_def: ToolDef | None, tf_prefix: str = '') -> list[LinkShape]:
    """The simulator's link shapes of a UR arm with its tool, and a small sphere at the tool tip."""
    model = mujoco.MjModel.from_xml_string(build_mjcf(robot, tf_prefix=tf_prefix, tool=tool_def))
    shapes = []
    for g in range(model.ngeom):
        body = model.body(model.geom_bodyid[g]).name
        mesh = _geom_mesh(int(model.geom_type[g]), model.geom_size[g])
        if mesh is None or model.geom_bodyid[g] == 0:
            continue
        pose = np.eye(4)
        pose[:3, :3] = trimesh.transformations.quaternion_matrix(model.geom_quat[g])[:3, :3]
        pose[:3, 3] = model.geom_pos[g]
        mesh.apply_transform(pose)
        is_tool = tool_def is not None and body == tf_prefix + tool_def.name
        shapes.append(LinkShape(body, mesh, TOOL_COLOR if is_tool else LINK_COLOR))
    if tool_def is not None:
        shapes.append(LinkShape(tf_prefix + tool_def.tip_name, trimesh.creation.icosphere(2, 0.005), TOOL_COLOR))
    return shapes


def _rod(a: np.ndarray, b: np.ndarray, radius: float) -> trimesh.Trimesh | None:
    length = float(np.linalg.norm(b - a))
    if length < 1e-6:
        return None
    rod = trimesh.creation.cylinder(radius=radius, height=length, sections=12)
    z = (b - a) / length
    axis = np.cross([0.0, 0.0, 1.0], z)
    angle = math.atan2(np.linalg.norm(axis), z[2])
    pose = trimesh.transformations.rotation_matrix(angle, axis) if np.linalg.norm(axis) > 1e-9 else \
        trimesh.transformations.rotation_matrix(math.pi if z[2] < 0 else 0.0, [1.0, 0.0, 0.0])
    pose[:3, 3] = (a + b) / 2.0
    rod.apply_transform(pose)
    return rod


def _numbers(origin: ET.Element | None, key: str) -> tuple[float, float, float]:
    text = origin.get(key, '0 0 0') if origin is not None else '0 0 0'
    return tuple(float(x) for x in text.split())


def urdf_shapes(urdf: str) -> list[LinkShape]:
    """Shapes of any URDF: its visual primitives, or a stick figure where a link has none."""
    root = ET.fromstring(urdf)
    shapes: list[LinkShape] = []
    with_visuals = set()
    for link in root.iter('link'):
        for visual in link.findall('visual'):
            geom = visual.find('geometry')
            pose = Origin(_numbers(visual.find('origin'), 'xyz'), _numbers(visual.find('origin'), 'rpy')).matrix()
            mesh = None
            if geom is not None and geom.find('box') is not None:
                mesh = trimesh.creation.box(extents=[float(x) for x in geom.find('box').get('size').split()])
            elif geom is not None and geom.find('cylinder') is not None:
                c = geom.find('cylinder')
                mesh = trimesh.creation.cylinder(radius=float(c.get('radius')), height=float(c.get('length')))
            elif geom is not None and geom.find('sphere') is not None:
                mesh = trimesh.creation.icosphere(2, float(geom.find('sphere').get('radius')))
            if mesh is not None:
                mesh.apply_transform(pose)
                shapes.append(LinkShape(link.get('name'), mesh, LINK_COLOR))
                with_visuals.add(link.get('name'))
    for joint in root.iter('joint'):
        parent = joint.find('parent').get('link')
        xyz = np.array(_numbers(joint.find('origin'), 'xyz'))
        if parent not in with_visuals:
            rod = _rod(np.zeros(3), xyz, STICK_RADIUS)
            if rod is not None:
                shapes.append(LinkShape(parent, rod, LINK_COLOR))
    return shapes


class RobotModel:
    """Link poses of a URDF at given joint positions, with shapes to draw.

    Args:
        urdf: URDF XML.
        shapes: Meshes per link; default :func:`shapes_for` the URDF.
    """

    def __init__(self, urdf: str, shapes: Sequence[LinkShape] | None = None) -> None:
        self.model = pin.buildModelFromXML(urdf)
        self.data = self.model.createData()
        self.shapes = list(shapes if shapes is not None else shapes_for(urdf))
        self.links = sorted({s.link for s in self.shapes})
        self._frame = {name: self.model.getFrameId(name) for name in self.links if self.model.existFrame(name)}
        self.joint_names = tuple(self.model.names[j] for j in range(1, self.model.njoints)
                                 if self.model.joints[j].nq == 1)
        self._qidx = {self.model.names[j]: self.model.joints[j].idx_q for j in range(1, self.model.njoints)
                      if self.model.joints[j].nq == 1}

    def q_full(self, names: Sequence[str], q: Sequence[float]) -> np.ndarray:
        """Pinocchio configuration from joint values by name (unknown names ignored, missing joints at 0)."""
        full = pin.neutral(self.model)
        for name, value in zip(names, q):
            idx = self._qidx.get(name)
            if idx is not None:
                full[idx] = value
        return full

    def link_poses(self, names: Sequence[str], q: Sequence[float]) -> dict[str, np.ndarray]:
        """World poses (4, 4) of the drawn links (URDF root = world)."""
        pin.framesForwardKinematics(self.model, self.data, self.q_full(names, q))
        return {name: self.data.oMf[fid].homogeneous.copy() for name, fid in self._frame.items()}

    def frame_position(self, frame: str, names: Sequence[str], q: Sequence[float]) -> np.ndarray | None:
        """World position (3,) [m] of ``frame`` (None if the URDF has no such frame)."""
        if not self.model.existFrame(frame):
            return None
        pin.framesForwardKinematics(self.model, self.data, self.q_full(names, q))
        return self.data.oMf[self.model.getFrameId(frame)].translation.copy()


def shapes_for(urdf: str) -> list[LinkShape]:
    """Our UR shapes when the URDF is one of our UR types (by its robot name and links), else its own shapes."""
    root = ET.fromstring(urdf)
    name = root.get('name', '')
    links = {link.get('name') for link in root.iter('link')}
    if name in UR_TYPES:
        prefix = next((ln[:-len('shoulder_link')] for ln in links if ln.endswith('shoulder_link')), '')
        tool = next((t for t in ('dispenser',) if prefix + t in links), None)
        return ur_shapes(load_ur_params(name), get_tool(tool), prefix)
    return urdf_shapes(urdf)


def tip_frame_of(urdf: str) -> str:
    """The frame whose path the live view traces: the mounted tool's tip (e.g. ``dispenser_tip``) when the URDF
    has one of our tools, else the flange ``tool0`` (with the URDF's prefix), else the deepest link of the tree."""
    root = ET.fromstring(urdf)
    links = [link.get('name') for link in root.iter('link')]
    prefix = next((ln[:-len('shoulder_link')] for ln in links if ln.endswith('shoulder_link')), '')
    tips = [get_tool(name).tip_name for name in TOOL_CHOICES if get_tool(name) is not None]
    for candidate in [prefix + tip for tip in tips] + [prefix + 'tool0']:
        if candidate in links:
            return candidate
    parent = {j.find('child').get('link'): j.find('parent').get('link') for j in root.iter('joint')}

    def depth(link: str) -> int:
        n = 0
        while link in parent and n < len(links):
            link, n = parent[link], n + 1
        return n
    return max(links, key=depth)
