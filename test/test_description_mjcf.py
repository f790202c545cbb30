"""Generated MJCF: agreement with the URDF (Pinocchio) and UR DH kinematics, dynamics,
actuators, collisions and static meshes."""

import math
import struct

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from ur_sim_driver.description.mjcf import PAYLOAD_BODY, add_static_mesh, build_mjcf
from ur_sim_driver.description.params import JOINT_NAMES, UR_TYPES, load_ur_params
from ur_sim_driver.description.tool import DISPENSER
from ur_sim_driver.description.urdf import build_urdf
from ur_sim_driver.errors import ConfigError

HOME = np.radians([0, -90, 0, -90, 0, 0])  # seed 1 home


def ur_dh_fk(dh, q):
    """Standard UR DH forward kinematics: DH end frame in the DH base frame (4, 4)."""
    alpha = (math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0)
    a, d = (0, dh.a2, dh.a3, 0, 0, 0), (dh.d1, 0, 0, dh.d4, dh.d5, dh.d6)
    out = np.eye(4)
    for i in range(6):
        ct, st, ca, sa = math.cos(q[i]), math.sin(q[i]), math.cos(alpha[i]), math.sin(alpha[i])
        out = out @ np.array([[ct, -st * ca, st * sa, a[i] * ct], [st, ct * ca, -ct * sa, a[i] * st],
                              [0, sa, ca, d[i]], [0, 0, 0, 1]])
    return out


def pose(xpos, xmat):
    out = np.eye(4)
    out[:3, :3] = np.reshape(xmat, (3, 3))
    out[:3, 3] = xpos
    return out


@pytest.fixture(scope='module', params=UR_TYPES)
def pair(request):
    p = load_ur_params(request.param)
    mj = mujoco.MjModel.from_xml_string(build_mjcf(p, tool=DISPENSER))
    pm = pin.buildModelFromXML(build_urdf(p, tool=DISPENSER))
    return p, mj, mujoco.MjData(mj), pm, pm.createData()


def test_frames_agree_with_pinocchio_and_dh(pair):
    p, mj, md, pm, pd = pair
    bodies = [mj.body(i).name for i in range(1, mj.nbody)]
    assert {'base', 'tool0', 'flange', 'ee_link', 'dispenser_tip'} <= set(bodies)
    rng = np.random.default_rng(7)
    for q in rng.uniform(p.q_min, p.q_max, (200, 6)):
        md.qpos[:] = q
        mujoco.mj_kinematics(mj, md)
        pin.framesForwardKinematics(pm, pd, q)
        for site in ('tool0', 'dispenser_tip'):
            np.testing.assert_allclose(pose(md.site(site).xpos, md.site(site).xmat),
                                       pd.oMf[pm.getFrameId(site)].homogeneous, atol=1e-9)
        base, tool0 = md.body('base'), md.site('tool0')
        np.testing.assert_allclose(np.linalg.inv(pose(base.xpos, base.xmat)) @ pose(tool0.xpos, tool0.xmat),
                                   ur_dh_fk(p.dh, q), atol=1e-9)
    for name in bodies:  # every link frame, checked at the last configuration
        # The payload body is MuJoCo's only (set_payload's mass at the flange): its frame is tool0's.
        frame = 'tool0' if name == PAYLOAD_BODY else name
        np.testing.assert_allclose(pose(md.body(name).xpos, md.body(name).xmat),
                                   pd.oMf[pm.getFrameId(frame)].homogeneous, atol=1e-9)


def test_gravity_and_mass_matrix_agree_with_pinocchio(pair):
    p, mj, md, pm, pd = pair
    rng = np.random.default_rng(8)
    mass = np.zeros((6, 6))
    for q in rng.uniform(-math.pi, math.pi, (50, 6)):
        md.qpos[:], md.qvel[:] = q, 0.0
        mujoco.mj_forward(mj, md)
        np.testing.assert_allclose(md.qfrc_bias, pin.rnea(pm, pd, q, np.zeros(6), np.zeros(6)), atol=1e-6)
        # The mass matrix tests the rotated inertia tensors, which gravity alone does not.
        _full_mass_matrix(mj, md, mass)
        np.testing.assert_allclose(mass, _sym(pin.crba(pm, pd, q)) + np.diag(p.armature), atol=1e-9)


def _full_mass_matrix(mj, md, out):
    try:
        mujoco.mj_fullM(mj, md, out)  # newer MuJoCo (d instead of d.qM)
    except TypeError:
        mujoco.mj_fullM(mj, out, md.qM)


def _sym(m):
    return np.triu(m) + np.triu(m, 1).T


def test_joints_and_actuators(pair):
    p, mj, _, _, _ = pair
    for i, name in enumerate(JOINT_NAMES):
        j, act = mj.joint(name), mj.actuator(name)
        np.testing.assert_allclose(j.range, [p.q_min[i], p.q_max[i]])
        assert j.armature[0] == p.armature[i] and mj.dof_damping[j.dofadr[0]] == p.damping[i]
        assert act.trntype[0] == mujoco.mjtTrn.mjTRN_JOINT and act.trnid[0] == j.id
        np.testing.assert_allclose(act.gear[0], 1.0)
        np.testing.assert_allclose(act.ctrlrange, [-p.effort_max[i], p.effort_max[i]])
        np.testing.assert_allclose(act.forcerange, [-p.effort_max[i], p.effort_max[i]])
        assert act.ctrllimited[0] and act.forcelimited[0]
    assert mj.nu == 6 and mj.nq == 6 and mj.opt.timestep == 0.002


def test_no_contacts_at_rest_poses_and_no_adjacent_contacts(pair):
    p, mj, md, _, _ = pair
    md.qpos[:] = HOME
    mujoco.mj_forward(mj, md)
    assert md.ncon == 0
    weld = mj.body_weldid
    adjacent = {frozenset((weld[b], weld[mj.body_parentid[weld[b]]])) for b in range(mj.nbody)}
    for q in np.random.default_rng(9).uniform(-math.pi, math.pi, (300, 6)):
        md.qpos[:] = q
        mujoco.mj_forward(mj, md)
        for c in md.contact[:md.ncon]:
            b1, b2 = weld[mj.geom_bodyid[c.geom1]], weld[mj.geom_bodyid[c.geom2]]
            assert b1 != b2 and frozenset((b1, b2)) not in adjacent


def test_self_collision_can_be_switched_off():
    mj = mujoco.MjModel.from_xml_string(build_mjcf(load_ur_params('ur10'), tool=DISPENSER, self_collision=False))
    md = mujoco.MjData(mj)
    floor_contacts = 0
    for q in np.random.default_rng(4).uniform(-math.pi, math.pi, (200, 6)):
        md.qpos[:] = q
        mujoco.mj_forward(mj, md)
        for c in md.contact[:md.ncon]:
            names = {mj.geom(c.geom1).name, mj.geom(c.geom2).name}
            assert 'floor' in names  # never robot against robot
            floor_contacts += 1
    assert floor_contacts > 0


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_prefix_and_base_pose(ur_type):
    # How long building and loading takes is bench/bench_description.py's (`make bench`).
    p = load_ur_params(ur_type)
    base_pose = np.eye(4)
    base_pose[:3, 3] = (0.1, 0.2, 0.5)
    base_pose[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    mj = mujoco.MjModel.from_xml_string(build_mjcf(p, 'r_', DISPENSER, base_pose, timestep=0.001))
    md = mujoco.MjData(mj)
    mujoco.mj_forward(mj, md)
    assert md.ncon == 0  # stretched out, half a metre above the floor
    ref = pin.buildModelFromXML(build_urdf(p))
    rd = ref.createData()
    pin.framesForwardKinematics(ref, rd, np.zeros(6))
    np.testing.assert_allclose(pose(md.site('r_tool0').xpos, md.site('r_tool0').xmat),
                               base_pose @ rd.oMf[ref.getFrameId('tool0')].homogeneous, atol=1e-9)
    assert mj.opt.timestep == 0.001
    assert mj.actuator('r_elbow_joint').trnid[0] == mj.joint('r_elbow_joint').id
    assert mj.site('r_dispenser_tip').id >= 0 and mj.body('r_base_link_inertia').id >= 0


def test_bad_timestep():
    with pytest.raises(ConfigError, match='timestep'):
        build_mjcf(load_ur_params('ur5'), timestep=0.0)


def _write_box_stl(path, half):
    """Binary STL of an axis-aligned box with half sizes ``half`` [m] centred at the origin."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
    with open(path, 'wb') as f:
        f.write(b'\0' * 80 + struct.pack('<I', len(faces)))
        for tri in faces:
            a, b, c = corners[list(tri)]
            n = np.cross(b - a, c - a)
            f.write(struct.pack('<12fH', *(n / np.linalg.norm(n)), *a, *b, *c, 0))


def test_add_static_mesh(tmp_path):
    stl = tmp_path / 'box.stl'
    _write_box_stl(stl, np.array([0.05, 0.05, 0.05]))
    p = load_ur_params('ur5')
    xml = build_mjcf(p, tool=DISPENSER)
    mj = mujoco.MjModel.from_xml_string(xml)
    md = mujoco.MjData(mj)
    md.qpos[:] = HOME
    mujoco.mj_kinematics(mj, md)
    where = np.eye(4)
    where[:3, :3] = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    where[:3, 3] = md.site('dispenser_tip').xpos + [0.0, -0.05, 0.0]  # engulfs the nozzle
    with_box = mujoco.MjModel.from_xml_string(add_static_mesh(xml, 'box', str(stl), where))
    bd = mujoco.MjData(with_box)
    bd.qpos[:] = HOME
    mujoco.mj_forward(with_box, bd)
    np.testing.assert_allclose(pose(bd.body('box').xpos, bd.body('box').xmat), where, atol=1e-12)
    touching = {with_box.geom(g).name for c in bd.contact[:bd.ncon] for g in (c.geom1, c.geom2)}
    assert 'box' in touching and 'dispenser_nozzle' in touching
    bd.qpos[:] = 0.0
    mujoco.mj_forward(with_box, bd)
    assert 'box' not in {with_box.geom(g).name for c in bd.contact[:bd.ncon] for g in (c.geom1, c.geom2)}
    with pytest.raises(ConfigError, match='box'):
        add_static_mesh(add_static_mesh(xml, 'box', stl, where), 'box', stl, where)
    with pytest.raises(ConfigError, match='missing.stl'):
        add_static_mesh(xml, 'glass', tmp_path / 'missing.stl', where)
    with pytest.raises(ConfigError):
        add_static_mesh(xml, 'glass', stl, np.diag([1.0, 1.0, -1.0, 1.0]))
