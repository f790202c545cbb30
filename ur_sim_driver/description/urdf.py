"""URDF of a UR arm with the ROS 2 ``ur_description`` frame tree, built from ``URParams``.

``kinematic_tree`` and ``link_inertials`` are the single definition of frames and masses;
``mjcf.build_mjcf`` uses them too, so Pinocchio (URDF) and MuJoCo (MJCF) agree exactly.

Frames (all names get ``tf_prefix``)::

    [world] -base_joint-> base_link -> base_link_inertia (rpy 0 0 pi) -> shoulder_link -> ...
    base_link -> base (rpy 0 0 pi: the UR controller's Base frame)
    ... -> wrist_3_link -> flange (rpy 0 -pi/2 -pi/2) -> tool0 (rpy pi/2 0 pi/2)
    wrist_3_link -> ft_frame (rpy pi 0 0);  flange -> ee_link (rpy pi 0 0, ROS-Industrial legacy)
    tool0 -> <tool> -> <tool tip>   (when a tool is given)
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from ur_sim_driver.description.params import JOINT_NAMES, LINK_NAMES, Origin, URParams
from ur_sim_driver.description.tool import ToolDef

WORLD_LINK = 'world'


@dataclass(frozen=True)
class JointSpec:
    """One URDF joint: ``child`` frame = ``parent`` frame * ``origin`` (* Rz(q) if revolute).

    ``index`` is the position in ``JOINT_NAMES`` for revolute joints, ``None`` for fixed ones.
    """

    name: str
    parent: str
    child: str
    origin: Origin
    index: int | None = None


@dataclass(frozen=True)
class Inertial:
    """Link inertia: ``mass`` [kg]; ``origin`` puts the com [m] and the axes of ``inertia``
    (ixx, ixy, ixz, iyy, iyz, izz) [kg m^2] in the link frame."""

    mass: float
    origin: Origin
    inertia: tuple[float, ...]

    def tensor_in_link(self) -> np.ndarray:
        """Inertia (3, 3) about the com, expressed in the link axes [kg m^2]."""
        xx, xy, xz, yy, yz, zz = self.inertia
        rot = self.origin.matrix()[:3, :3]
        return rot @ np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]) @ rot.T


def kinematic_tree(params: URParams, tf_prefix: str = '', tool: ToolDef | None = None,
                   base_pose: np.ndarray | None = None) -> tuple[JointSpec, ...]:
    """All joints, parents listed before their children; the root is ``world`` when
    ``base_pose`` (4, 4) is given, else ``base_link``."""
    p, hp = tf_prefix, math.pi / 2
    joints = []
    if base_pose is not None:
        joints.append(JointSpec(p + 'base_joint', WORLD_LINK, p + 'base_link', Origin.from_matrix(base_pose)))
    joints += [
        JointSpec(p + 'base_link-base_link_inertia', p + 'base_link', p + 'base_link_inertia',
                  Origin(rpy=(0.0, 0.0, math.pi))),
        JointSpec(p + 'base_link-base_fixed_joint', p + 'base_link', p + 'base', Origin(rpy=(0.0, 0.0, math.pi))),
    ]
    parent = p + 'base_link_inertia'
    for i, origin in enumerate(params.joint_origins()):
        joints.append(JointSpec(p + JOINT_NAMES[i], parent, p + LINK_NAMES[i], origin, i))
        parent = p + LINK_NAMES[i]
    joints += [
        JointSpec(p + 'wrist_3_link-ft_frame', parent, p + 'ft_frame', Origin(rpy=(math.pi, 0.0, 0.0))),
        JointSpec(p + 'wrist_3-flange', parent, p + 'flange', Origin(rpy=(0.0, -hp, -hp))),
        JointSpec(p + 'flange-tool0', p + 'flange', p + 'tool0', Origin(rpy=(hp, 0.0, hp))),
        JointSpec(p + 'ee_fixed_joint', p + 'flange', p + 'ee_link', Origin(rpy=(math.pi, 0.0, 0.0))),
    ]
    if tool is not None:
        joints += [
            JointSpec(f'{p}tool0-{tool.name}', p + 'tool0', p + tool.name, tool.mount),
            JointSpec(f'{p}{tool.name}-{tool.tip_name}', p + tool.name, p + tool.tip_name, tool.tip),
        ]
    return tuple(joints)


def link_inertials(params: URParams, tf_prefix: str = '', tool: ToolDef | None = None) -> dict[str, Inertial]:
    """Inertials of the links that have mass, keyed by (prefixed) link name."""
    m, r, h = params.base_mass, params.base_radius, params.base_length
    across = m * (3 * r * r + h * h) / 12.0  # ur_description's cylinder_inertial
    out = {tf_prefix + 'base_link_inertia': Inertial(m, Origin(), (across, 0.0, 0.0, across, 0.0, 0.5 * m * r * r))}
    for i, link in enumerate(LINK_NAMES):
        out[tf_prefix + link] = Inertial(
            float(params.masses[i]),
            Origin(tuple(float(v) for v in params.coms[i]), tuple(float(v) for v in params.inertia_rpy[i])),
            tuple(float(v) for v in params.inertias[i]))
    if tool is not None:
        out[tf_prefix + tool.name] = Inertial(tool.mass, Origin(tool.com), tool.inertia)
    return out


def fmt(values) -> str:
    """Numbers as a space separated string with round-trip precision."""
    return ' '.join(repr(float(v)) for v in np.atleast_1d(values))


def build_urdf(params: URParams, tf_prefix: str = '', tool: ToolDef | None = None,
               base_pose: np.ndarray | None = None) -> str:
    """URDF (XML string) of ``params`` with optional ``tool`` and ``base_pose`` (4, 4) of
    ``base_link`` in ``world``. Revolute joints carry position [rad], velocity [rad/s] and
    effort [N m] limits and the simulation's viscous damping [N m s/rad]."""
    robot = ET.Element('robot', name=params.name)
    tree = kinematic_tree(params, tf_prefix, tool, base_pose)
    inertials = link_inertials(params, tf_prefix, tool)
    links = [tree[0].parent] + [j.child for j in tree]
    for name in links:
        link = ET.SubElement(robot, 'link', name=name)
        if name in inertials:
            inn = inertials[name]
            el = ET.SubElement(link, 'inertial')
            ET.SubElement(el, 'origin', xyz=fmt(inn.origin.xyz), rpy=fmt(inn.origin.rpy))
            ET.SubElement(el, 'mass', value=fmt(inn.mass))
            ET.SubElement(el, 'inertia', **dict(zip(('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz'),
                                                     (fmt(v) for v in inn.inertia))))
    for j in tree:
        joint = ET.SubElement(robot, 'joint', name=j.name, type='fixed' if j.index is None else 'revolute')
        ET.SubElement(joint, 'parent', link=j.parent)
        ET.SubElement(joint, 'child', link=j.child)
        ET.SubElement(joint, 'origin', xyz=fmt(j.origin.xyz), rpy=fmt(j.origin.rpy))
        if j.index is not None:
            i = j.index
            ET.SubElement(joint, 'axis', xyz='0 0 1')
            ET.SubElement(joint, 'limit', lower=fmt(params.q_min[i]), upper=fmt(params.q_max[i]),
                          effort=fmt(params.effort_max[i]), velocity=fmt(params.v_max[i]))
            ET.SubElement(joint, 'dynamics', damping=fmt(params.damping[i]), friction='0.0')
    ET.indent(robot)
    return '<?xml version="1.0"?>\n' + ET.tostring(robot, encoding='unicode') + '\n'
