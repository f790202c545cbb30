"""Generated URDF: frame tree, limits, inertials, and kinematics through Pinocchio."""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from ur_sim_driver.description.params import JOINT_NAMES, UR_TYPES, load_ur_params
from ur_sim_driver.description.tool import DISPENSER
from ur_sim_driver.description.urdf import build_urdf


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def ur_dh_fk(dh, q):
    """Standard UR DH forward kinematics: pose (4, 4) of the DH end frame in the DH base."""
    alpha = (math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0)
    a = (0, dh.a2, dh.a3, 0, 0, 0)
    d = (dh.d1, 0, 0, dh.d4, dh.d5, dh.d6)
    out = np.eye(4)
    for i in range(6):
        ct, st, ca, sa = math.cos(q[i]), math.sin(q[i]), math.cos(alpha[i]), math.sin(alpha[i])
        out = out @ np.array([[ct, -st * ca, st * sa, a[i] * ct],
                              [st, ct * ca, -ct * sa, a[i] * st],
                              [0, sa, ca, d[i]],
                              [0, 0, 0, 1]])
    return out


def frame(model, data, name):
    return data.oMf[model.getFrameId(name)].homogeneous


@pytest.fixture(scope='module', params=UR_TYPES)
def robot(request):
    p = load_ur_params(request.param)
    model = pin.buildModelFromXML(build_urdf(p, tool=DISPENSER))
    return p, model, model.createData()


def test_tool0_agrees_with_ur_dh(robot):
    p, model, data = robot
    rng = np.random.default_rng(11)
    tip = np.eye(4)
    tip[:3, 3] = (0.04, 0.0, 0.195)
    tip[:3, :3] = rot_x(math.pi / 2)  # DESIGN.md section 6
    for q in rng.uniform(p.q_min, p.q_max, (200, 6)):
        pin.framesForwardKinematics(model, data, q)
        base, tool0 = frame(model, data, 'base'), frame(model, data, 'tool0')
        np.testing.assert_allclose(np.linalg.inv(base) @ tool0, ur_dh_fk(p.dh, q), atol=1e-9)
        np.testing.assert_allclose(frame(model, data, 'dispenser_tip'), tool0 @ tip, atol=1e-9)


def test_fixed_frames(robot):
    p, model, data = robot
    q = np.random.default_rng(5).uniform(-3, 3, 6)
    pin.framesForwardKinematics(model, data, q)
    f = lambda n: frame(model, data, n)  # noqa: E731
    rel = lambda a, b: np.linalg.inv(f(a)) @ f(b)  # noqa: E731
    np.testing.assert_allclose(f('base_link'), np.eye(4), atol=1e-15)
    np.testing.assert_allclose(rel('base_link', 'base')[:3, :3], rot_z(math.pi), atol=1e-12)
    np.testing.assert_allclose(rel('base_link', 'base_link_inertia')[:3, :3], rot_z(math.pi), atol=1e-12)
    np.testing.assert_allclose(rel('flange', 'ee_link')[:3, :3], rot_x(math.pi), atol=1e-12)
    np.testing.assert_allclose(rel('flange', 'tool0')[:3, :3], rot_z(math.pi / 2) @ rot_x(math.pi / 2), atol=1e-12)
    np.testing.assert_allclose(rel('wrist_3_link', 'flange')[:3, :3],
                               rot_z(-math.pi / 2) @ rot_y(-math.pi / 2), atol=1e-12)
    for a, b in [('base_link', 'base'), ('flange', 'ee_link'), ('flange', 'tool0'), ('wrist_3_link', 'flange')]:
        np.testing.assert_allclose(rel(a, b)[:3, 3], 0.0, atol=1e-12)
    # Flange x points out of the flange, i.e. along tool0 z.
    np.testing.assert_allclose(f('flange')[:3, 0], f('tool0')[:3, 2], atol=1e-12)


def test_seed2_ee_link_pose():
    """Seed 2: FK of the course's IK answer puts ee_link at (0.6, 0, 0) in base_link, with
    ZYX Euler angles (pi/4, pi/4, -pi/4); the answer is printed with 4 decimals."""
    model = pin.buildModelFromXML(build_urdf(load_ur_params('ur10')))
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.array([-0.3824, 0.9804, -2.0033, 2.22, 0.8626, 1.3279]))
    ee = frame(model, data, 'ee_link')
    np.testing.assert_allclose(ee[:3, 3], [0.6, 0.0, 0.0], atol=1e-4)
    np.testing.assert_allclose(ee[:3, :3], rot_z(math.pi / 4) @ rot_y(math.pi / 4) @ rot_x(-math.pi / 4), atol=1e-4)


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_limits_inertials_and_names(ur_type):
    p = load_ur_params(ur_type)
    root = ET.fromstring(build_urdf(p, tf_prefix='left_', tool=DISPENSER))
    links = {el.get('name') for el in root.iter('link')}
    assert {'left_base_link', 'left_base', 'left_base_link_inertia', 'left_flange', 'left_tool0',
            'left_ee_link', 'left_dispenser', 'left_dispenser_tip', 'left_wrist_3_link'} <= links
    assert all(n.startswith('left_') for n in links)
    revolute = [j for j in root.iter('joint') if j.get('type') == 'revolute']
    assert [j.get('name') for j in revolute] == ['left_' + n for n in JOINT_NAMES]
    for i, j in enumerate(revolute):
        lim = j.find('limit')
        assert float(lim.get('lower')) == p.q_min[i] and float(lim.get('upper')) == p.q_max[i]
        assert float(lim.get('velocity')) == p.v_max[i] and float(lim.get('effort')) == p.effort_max[i]
        assert j.find('axis').get('xyz') == '0 0 1'
    model = pin.buildModelFromXML(ET.tostring(root, encoding='unicode'))
    moving_mass = sum(model.inertias[i].mass for i in range(1, model.njoints))
    assert moving_mass == pytest.approx(p.masses.sum() + DISPENSER.mass, abs=1e-12)
    np.testing.assert_allclose(model.velocityLimit, p.v_max)
    np.testing.assert_allclose(model.effortLimit, p.effort_max)


def test_base_pose_places_base_link_in_world():
    p = load_ur_params('ur5')
    pose = np.eye(4)
    pose[:3, :3] = rot_z(0.3) @ rot_y(-0.2) @ rot_x(0.1)
    pose[:3, 3] = (0.2, -0.4, 1.0)
    placed = pin.buildModelFromXML(build_urdf(p, base_pose=pose))
    plain = pin.buildModelFromXML(build_urdf(p))
    dp, dn = placed.createData(), plain.createData()
    q = np.random.default_rng(2).uniform(-3, 3, 6)
    pin.framesForwardKinematics(placed, dp, q)
    pin.framesForwardKinematics(plain, dn, q)
    np.testing.assert_allclose(frame(placed, dp, 'tool0'), pose @ frame(plain, dn, 'tool0'), atol=1e-12)
    assert placed.existFrame('world')


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_builds_and_loads_with_the_tool(ur_type):
    # How long building and loading takes is bench/bench_description.py's (`make bench`).
    model = pin.buildModelFromXML(build_urdf(load_ur_params(ur_type), tool=DISPENSER))
    assert model.nq == 6
