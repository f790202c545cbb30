"""MuJoCo model (MJCF) of a UR arm, built from the same frame tree and inertials as the URDF.

Every URDF link is a MuJoCo body of the same name whose pos/quat is the URDF joint origin, and
every revolute joint is a hinge about the body's z axis, so body frames equal link frames and
forward kinematics agrees with Pinocchio to rounding. The arm is torque driven: one ``<motor>``
per joint (named like the joint, gear 1, control and force clamped to the effort limit); the
simulator closes the loop (computed torque + PD) itself.

Joint dynamics not in UR's published data (values per type in ``config/ur_types/*.yaml``,
``simulation`` section, also exposed as ``URParams.armature`` / ``URParams.damping``):

* armature (reflected rotor inertia, [kg m^2]): rotor inertia times the square of the
  harmonic drive ratio (about 100:1), i.e. about 1e-5 kg m^2 * 1e4 = 0.1 for the size-3 joints
  (UR5 base/shoulder/elbow, UR10 elbow), 0.25 for the size-4 UR10 base/shoulder, 0.03 / 0.015
  for the size-2 / size-1 wrists. Besides realism it keeps the very light wrist_3 (inertia
  ~1e-4 kg m^2) stable under stiff PD gains at a 2 ms step. A model-based controller should add
  it to its mass matrix (Pinocchio: ``model.armature``); MuJoCo's ``qM`` already contains it.
* damping (viscous joint friction, [N m s/rad]): 1.0 (size 3), 2.0 (size 4), 0.5 / 0.3 (size
  2 / 1) as a modest stand-in for gear friction; it appears in ``qfrc_passive``, not
  ``qfrc_bias``, so gravity compensation at rest is unaffected.

The integrator is ``implicitfast``, which treats the damping implicitly (stable at 2 ms).

Coulomb joint friction (``URParams.coulomb``) is not in the model: the robot's servo cancels it. Under torque
control the simulator sets what the robot's compensation leaves as MuJoCo's ``frictionloss``, a soft constraint;
its solver parameters here make it stiff (:data:`FRICTION_SOLREF`, :data:`FRICTION_SOLIMP`), so that a joint held
by friction creeps by less than 1e-4 rad/s instead of MuJoCo's default 0.02 rad/s.

Collision shapes are capsules and cylinders roughly the size of the real links (radii in the
YAML). Contacts between a body and its parent are filtered by MuJoCo; pairs that touch by
construction in the compact wrist and at the base are excluded explicitly. Other self-contacts
stay enabled unless ``self_collision=False``. Links do collide with the floor and with static
meshes added by ``add_static_mesh``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ur_common.quaternions import quat_from_matrix
from ur_sim_driver.description.params import Origin, URParams
from ur_sim_driver.description.tool import ToolDef
from ur_sim_driver.description.urdf import WORLD_LINK, fmt, kinematic_tree, link_inertials
from ur_sim_driver.errors import ConfigError

# Coulomb friction's constraint: time constant [s] (MuJoCo raises it to two physics steps) and impedance.
FRICTION_SOLREF = '0.004 1'
FRICTION_SOLIMP = '0.999 0.999 0.001'

# (contype, conaffinity). Environment geoms set both bits, so every robot geom meets them.
# Robot geoms use bit 0 on both sides to also meet each other, or contype bit 1 with
# conaffinity bit 0 to meet the environment only (self_collision=False).
_ENV_BITS = ('3', '3')
_ROBOT_BITS = {True: ('1', '1'), False: ('2', '1')}
# Pairs in contact by construction (the parent filter does not cover them).
# Names (after tf_prefix) of the run-time payload body and of the flange force-torque sensor's two halves.
PAYLOAD_BODY = 'payload'
FT_FORCE_SENSOR = 'tcp_fts_force'
FT_TORQUE_SENSOR = 'tcp_fts_torque'
# Names (after tf_prefix) of the frame sensors giving the tool0 site's pose in the base body: MuJoCo computes it
# with the positions (mj_step1), so the TCP pose needs no rotation code of ours.
TCP_POSITION_SENSOR = 'tcp_pose_position'
TCP_ORIENTATION_SENSOR = 'tcp_pose_orientation'
_EXCLUDES = (('base_link_inertia', 'shoulder_link'), ('forearm_link', 'wrist_2_link'),
             ('wrist_1_link', 'wrist_3_link'))


def _collision_shapes(params: URParams) -> dict[str, list[tuple[str, float, tuple[float, ...]]]]:
    """(type, radius, fromto [m]) per unprefixed link, in the link frame."""
    d, r = params.dh, params.collision_radius
    so, eo = params.shoulder_offset, params.elbow_offset
    base_top = max(0.01, d.d1 - r['shoulder'] - 0.005)  # stays below the shoulder-lift housing

    def z(a: float, b: float) -> tuple[float, ...]:  # segment along the link's z (joint) axis
        return (0.0, 0.0, a, 0.0, 0.0, b)

    return {
        'base_link_inertia': [('cylinder', r['base'], z(0.0, base_top))],
        'shoulder_link': [('cylinder', r['shoulder'], z(base_top - d.d1, 0.0))],
        'upper_arm_link': [('cylinder', r['shoulder'], z(-0.5 * r['shoulder'], so)),
                           ('capsule', r['upper_arm'], (0.0, 0.0, so, d.a2, 0.0, so))],
        'forearm_link': [('cylinder', r['elbow'], z(eo - r['forearm'], so)),
                         ('capsule', r['forearm'], (0.0, 0.0, eo, d.a3, 0.0, eo))],
        'wrist_1_link': [('capsule', r['wrist'], z(eo - d.d4, 0.0))],
        'wrist_2_link': [('capsule', r['wrist'], z(-d.d5, 0.0))],
        'wrist_3_link': [('cylinder', r['wrist'], z(-d.d6, 0.0))],
    }


def _pose_attrs(origin: Origin) -> dict[str, str]:
    return {'pos': fmt(origin.xyz), 'quat': fmt(quat_from_matrix(origin.matrix()[:3, :3]))}


def build_mjcf(params: URParams, tf_prefix: str = '', tool: ToolDef | None = None,
               base_pose: np.ndarray | None = None, timestep: float = 0.002,
               self_collision: bool = True) -> str:
    """MJCF (XML string) of ``params`` with optional ``tool``, ``base_pose`` (4, 4) of
    ``base_link`` in the world, physics ``timestep`` [s]; a floor plane at world z = 0.

    Names: bodies = URDF links, hinges and motors = URDF joints, sites ``tool0`` and the tool
    tip, the massless body ``payload`` fixed at tool0 (``PAYLOAD_BODY``, for set_payload) and
    the force and torque sensors at the tool0 site (``FT_FORCE_SENSOR``, ``FT_TORQUE_SENSOR``), the tool0 site's
    position and orientation in the base body (``TCP_POSITION_SENSOR``, ``TCP_ORIENTATION_SENSOR``),
    all with ``tf_prefix``.
    """
    if not (np.isfinite(timestep) and timestep > 0.0):
        raise ConfigError(f'timestep must be > 0 s, got {timestep!r}')
    p = tf_prefix
    root = ET.Element('mujoco', model=params.name)
    ET.SubElement(root, 'compiler', angle='radian', autolimits='true', inertiafromgeom='false')
    ET.SubElement(root, 'option', timestep=fmt(timestep), integrator='implicitfast')
    ET.SubElement(root, 'asset')
    world = ET.SubElement(root, 'worldbody')
    ET.SubElement(world, 'light', name=p + 'sun', pos='0 0 3', dir='0 0 -1', directional='true')
    ET.SubElement(world, 'geom', name=p + 'floor', type='plane', size='0 0 0.05', rgba='0.8 0.8 0.8 1',
                  contype=_ENV_BITS[0], conaffinity=_ENV_BITS[1])

    bodies: dict[str, ET.Element] = {WORLD_LINK: world}
    tree = kinematic_tree(params, p, tool, base_pose)
    if tree[0].parent != WORLD_LINK:  # no base_pose: base_link is the world frame
        bodies[tree[0].parent] = ET.SubElement(world, 'body', name=tree[0].parent)
    for j in tree:
        bodies[j.child] = ET.SubElement(bodies[j.parent], 'body', name=j.child, **_pose_attrs(j.origin))
        if j.index is not None:
            i = j.index
            ET.SubElement(bodies[j.child], 'joint', name=j.name, type='hinge', axis='0 0 1',
                          range=fmt([params.q_min[i], params.q_max[i]]), armature=fmt(params.armature[i]),
                          damping=fmt(params.damping[i]), solreffriction=FRICTION_SOLREF,
                          solimpfriction=FRICTION_SOLIMP)

    for link, inn in link_inertials(params, p, tool).items():
        t = inn.tensor_in_link()
        el = ET.Element('inertial', pos=fmt(inn.origin.xyz), mass=fmt(inn.mass),
                        fullinertia=fmt([t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2]]))
        bodies[link].insert(0, el)

    contype, conaff = _ROBOT_BITS[bool(self_collision)]
    for link, shapes in _collision_shapes(params).items():
        for k, (kind, radius, fromto) in enumerate(shapes):
            ET.SubElement(bodies[p + link], 'geom', name=f'{p}{link}_collision_{k}', type=kind,
                          size=fmt(radius), fromto=fmt(fromto), contype=contype, conaffinity=conaff,
                          rgba='0.6 0.65 0.7 1')
    ET.SubElement(bodies[p + 'tool0'], 'site', name=p + 'tool0', size='0.005')
    # The payload set at run time (set_payload): massless until then, fixed at tool0.
    ET.SubElement(bodies[p + 'tool0'], 'body', name=p + PAYLOAD_BODY)
    if tool is not None:
        for g in tool.geoms:
            ET.SubElement(bodies[p + tool.name], 'geom', name=p + g.name, type='cylinder',
                          size=fmt([g.radius, g.length / 2]), contype=contype, conaffinity=conaff,
                          rgba='0.9 0.5 0.1 1', **_pose_attrs(g.origin))
        ET.SubElement(bodies[p + tool.tip_name], 'site', name=p + tool.tip_name, size='0.004')

    contact = ET.SubElement(root, 'contact')
    for a, b in _EXCLUDES:
        ET.SubElement(contact, 'exclude', body1=p + a, body2=p + b)
    actuators = ET.SubElement(root, 'actuator')
    for j in tree:
        if j.index is not None:
            lim = fmt([-params.effort_max[j.index], params.effort_max[j.index]])
            ET.SubElement(actuators, 'motor', name=j.name, joint=j.name, gear='1', ctrlrange=lim, forcerange=lim)
    # The flange's force-torque sensor: what the subtree beyond tool0 (tool, payload, their contacts)
    # exchanges with the arm, at and in the tool0 site.
    sensors = ET.SubElement(root, 'sensor')
    ET.SubElement(sensors, 'force', name=p + FT_FORCE_SENSOR, site=p + 'tool0')
    ET.SubElement(sensors, 'torque', name=p + FT_TORQUE_SENSOR, site=p + 'tool0')
    # reftype xbody: the base body's frame ('body' would be the frame of its inertia)
    tcp = {'objtype': 'site', 'objname': p + 'tool0', 'reftype': 'xbody', 'refname': p + 'base'}
    ET.SubElement(sensors, 'framepos', name=p + TCP_POSITION_SENSOR, **tcp)
    ET.SubElement(sensors, 'framequat', name=p + TCP_ORIENTATION_SENSOR, **tcp)
    ET.indent(root)
    return ET.tostring(root, encoding='unicode') + '\n'


def add_static_mesh(mjcf_xml: str, name: str, stl_path: str | Path, pose: np.ndarray,
                    collide: bool = True) -> str:
    """Return ``mjcf_xml`` with a fixed body ``name`` showing the STL mesh at ``stl_path``
    (units [m]) placed at ``pose`` (4, 4) in the world. The geom (also named ``name``) collides
    with the robot unless ``collide`` is False (contype = conaffinity = 0: visual only).

    Note: MuJoCo collides a mesh as its convex hull, so a strongly curved (concave) part
    should be added as several convex pieces (e.g. the windshield's ``windshield_piece_XX``),
    with the whole mesh added with ``collide=False`` for display.
    """
    path = Path(stl_path).resolve()
    if not path.is_file():
        raise ConfigError(f'mesh file {str(path)!r} does not exist')
    Origin.from_matrix(pose)  # raises ConfigError unless a proper rigid transform
    pose = np.asarray(pose, dtype=float)
    pos_quat = {'pos': fmt(pose[:3, 3]), 'quat': fmt(quat_from_matrix(pose[:3, :3]))}
    try:
        root = ET.fromstring(mjcf_xml)
    except ET.ParseError as exc:
        raise ConfigError(f'mjcf_xml is not valid XML: {exc}') from exc
    if any(el.get('name') == name for el in root.iter('body')) or \
            any(el.get('name') == name for el in root.iter('mesh')):
        raise ConfigError(f'a body or mesh named {name!r} already exists in the model')
    asset = root.find('asset')
    if asset is None:
        asset = ET.Element('asset')
        root.insert(0, asset)
    ET.SubElement(asset, 'mesh', name=name, file=str(path))
    world = root.find('worldbody')
    if world is None:
        raise ConfigError('mjcf_xml has no <worldbody>')
    body = ET.SubElement(world, 'body', name=name, **pos_quat)
    contype, conaffinity = _ENV_BITS if collide else ('0', '0')
    ET.SubElement(body, 'geom', name=name, type='mesh', mesh=name, contype=contype,
                  conaffinity=conaffinity, rgba='0.55 0.75 0.9 0.6')
    ET.indent(root)
    return ET.tostring(root, encoding='unicode') + '\n'
