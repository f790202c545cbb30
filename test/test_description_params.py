"""UR type parameter files and their loader (no ROS needed)."""

import math
import re

import numpy as np
import pytest

from ur_common.quaternions import quat_from_matrix
from ur_sim_driver.description import params as params_mod
from ur_sim_driver.description.params import (
    JOINT_NAMES,
    UR_TYPES,
    Origin,
    config_dir,
    joint_names,
    load_ur_params,
    matrix_to_rpy,
    rpy_to_matrix,
)
from ur_sim_driver.errors import ConfigError

# Universal Robots' published numbers (DESIGN.md section 5; for the other types UR's article "DH parameters for
# calculations of kinematics and dynamics" and the user manuals' joint tables), typed in independently of the files.
# The ur7e is the ur5e arm and the ur12e the ur10e arm with a higher rated payload. The UR Series' masses are the
# description's (its UR20 wrist 3 weighs 0.926 kg where the DH article says 0.846).
DESIGN = {
    'ur8long': dict(dh=(0.2186, -0.8989, -0.7149, 0.1824, 0.1361, 0.1434),
                    masses=(9.9883, 17.0738, 7.6393, 2.089, 2.0869, 1.0666), speed=(180, 180, 240, 300, 300, 300),
                    effort=(433, 433, 204, 70, 70, 70), rate=500.0),
    'ur15': dict(dh=(0.2186, -0.6475, -0.5164, 0.1824, 0.1361, 0.1434),
                 masses=(9.9883, 14.9255, 6.1015, 2.089, 2.0869, 1.0666), speed=(180, 180, 240, 300, 300, 300),
                 effort=(433, 433, 204, 70, 70, 70), rate=500.0),
    'ur18': dict(dh=(0.2186, -0.475, -0.3389, 0.1824, 0.1361, 0.1434),
                 masses=(9.9883, 14.2009, 5.52, 2.089, 2.0869, 1.0666), speed=(180, 180, 240, 300, 300, 300),
                 effort=(433, 433, 204, 70, 70, 70), rate=500.0),
    'ur20': dict(dh=(0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
                 masses=(16.343, 29.632, 7.879, 3.054, 3.126, 0.926), speed=(120, 120, 150, 210, 210, 210),
                 effort=(738, 738, 433, 107, 107, 107), rate=500.0),
    'ur30': dict(dh=(0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
                 masses=(16.343, 28.542, 7.156, 3.054, 3.126, 0.926), speed=(120, 120, 150, 210, 210, 210),
                 effort=(738, 738, 433, 107, 107, 107), rate=500.0),
    'ur3': dict(dh=(0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
                masses=(2.0, 3.42, 1.26, 0.8, 0.8, 0.35), speed=(180, 180, 180, 360, 360, 360),
                effort=(56, 56, 28, 12, 12, 12), rate=125.0),
    'ur3e': dict(dh=(0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
                 masses=(1.98, 3.4445, 1.437, 0.871, 0.805, 0.261), speed=(180, 180, 180, 360, 360, 360),
                 effort=(54, 54, 28, 9, 9, 9), rate=500.0),
    'ur7e': dict(dh=(0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
                 masses=(3.761, 8.058, 2.846, 1.37, 1.3, 0.365), speed=(180,) * 6,
                 effort=(150, 150, 150, 28, 28, 28), rate=500.0),
    'ur12e': dict(dh=(0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
                  masses=(7.369, 13.051, 3.989, 2.1, 1.98, 0.615), speed=(120, 120, 180, 180, 180, 180),
                  effort=(330, 330, 150, 54, 54, 54), rate=500.0),
    'ur16e': dict(dh=(0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
                  masses=(7.369, 10.45, 4.321, 2.18, 2.033, 0.907), speed=(120, 120, 180, 180, 180, 180),
                  effort=(330, 330, 150, 54, 54, 54), rate=500.0),
    'ur5': dict(dh=(0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
                masses=(3.7, 8.393, 2.33, 1.219, 1.219, 0.1879), speed=(180,) * 6,
                effort=(150, 150, 150, 28, 28, 28), rate=125.0),
    'ur5e': dict(dh=(0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
                 masses=(3.761, 8.058, 2.846, 1.37, 1.3, 0.365), speed=(180,) * 6,
                 effort=(150, 150, 150, 28, 28, 28), rate=500.0),
    'ur10': dict(dh=(0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
                 masses=(7.1, 12.7, 4.27, 2.0, 2.0, 0.365), speed=(120, 120, 180, 180, 180, 180),
                 effort=(330, 330, 150, 56, 56, 56), rate=125.0),
    'ur10e': dict(dh=(0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
                  masses=(7.369, 13.051, 3.989, 2.1, 1.98, 0.615), speed=(120, 120, 180, 180, 180, 180),
                  effort=(330, 330, 150, 54, 54, 54), rate=500.0),
}


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_published_numbers(ur_type):
    p, ref = load_ur_params(ur_type), DESIGN[ur_type]
    d = p.dh
    assert (d.d1, d.a2, d.a3, d.d4, d.d5, d.d6) == ref['dh']
    np.testing.assert_array_equal(p.masses, ref['masses'])
    np.testing.assert_allclose(p.v_max, np.radians(ref['speed']), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(p.effort_max, ref['effort'])
    assert p.control_rate == ref['rate']
    assert p.a_max == 5.0
    limits = np.radians([360, 360, 180, 360, 360, 360])
    np.testing.assert_allclose(p.q_max, limits, atol=1e-15)
    np.testing.assert_allclose(p.q_min, -limits, atol=1e-15)
    assert p.name == ur_type


@pytest.mark.parametrize('ur_type', UR_TYPES)
def test_shapes_read_only_and_physical(ur_type):
    p = load_ur_params(ur_type)
    shapes = dict(masses=(6,), coms=(6, 3), inertias=(6, 6), inertia_rpy=(6, 3), q_min=(6,), q_max=(6,),
                  v_max=(6,), effort_max=(6,), armature=(6,), damping=(6,), coulomb=(6,))
    for name, shape in shapes.items():
        arr = getattr(p, name)
        assert arr.shape == shape, name
        with pytest.raises(ValueError):
            arr[0] = 1.0
    for xx, xy, xz, yy, yz, zz in p.inertias:
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        eig = np.linalg.eigvalsh(tensor)
        assert eig.min() > 0 and 2 * eig.max() <= eig.sum() + 1e-12  # triangle inequality
    assert np.all(p.armature > 0) and np.all(p.damping >= 0)
    assert set(p.collision_radius) == {'base', 'shoulder', 'upper_arm', 'elbow', 'forearm', 'wrist'}
    with pytest.raises(TypeError):
        p.collision_radius['base'] = 1.0


def test_joint_names():
    assert JOINT_NAMES == ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
                           'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint')
    assert joint_names('ur_')[0] == 'ur_shoulder_pan_joint' and len(joint_names('ur_')) == 6


@pytest.mark.parametrize('bad', ['ur6', 'UR5x', '', 5, None])
def test_unknown_type_names_value_and_choices(bad):
    with pytest.raises(ConfigError) as err:
        load_ur_params(bad)
    msg = str(err.value)
    assert repr(bad) in msg
    assert all(t in msg for t in UR_TYPES)


def test_type_is_case_insensitive():
    assert load_ur_params(' UR10e ').name == 'ur10e'


def test_every_number_in_the_yaml_names_a_source_the_header_defines():
    number = re.compile(r'[-+]?\d+\.\d*|[-+]?\d+e[-+]?\d+|:\s*[-+]?\d+\s*($|#)')
    tag = re.compile(r'\[([A-Z][A-Z0-9]*)\]')
    paths = sorted(config_dir().glob('ur*.yaml'))
    assert [p.stem for p in paths] == sorted(UR_TYPES)
    for path in paths:
        lines = path.read_text().splitlines()
        defined = {m.group(1) for line in lines if (m := re.match(r'#\s+\[([A-Z][A-Z0-9]*)\]', line))}
        for n, line in enumerate(lines, 1):
            code, _, comment = line.partition('#')
            if number.search(code):
                used = set(tag.findall(comment))
                assert used, f'{path.name}:{n}: {line}'
                assert used <= defined, f'{path.name}:{n}: {sorted(used - defined)} not defined in the header'


def test_malformed_yaml_is_a_config_error(tmp_path, monkeypatch):
    good = (config_dir() / 'ur5.yaml').read_text()
    (tmp_path / 'ur5.yaml').write_text(good.replace('d4: 0.10915', 'd4: [oops'))
    (tmp_path / 'ur10.yaml').write_text(good.replace('  effort: [150.0, 150.0, 150.0, 28.0, 28.0, 28.0]',
                                                     '  effort: [150.0, 28.0]'))
    (tmp_path / 'ur10e.yaml').write_text(good.replace('velocity_deg_s: [180.0, 180.0,',
                                                      'velocity_deg_s: [180.0, -180.0,'))
    monkeypatch.setattr(params_mod, 'config_dir', lambda: tmp_path)
    params_mod._load.cache_clear()
    try:
        with pytest.raises(ConfigError, match='ur5.yaml'):
            load_ur_params('ur5')
        with pytest.raises(ConfigError, match='effort'):
            load_ur_params('ur10')
        with pytest.raises(ConfigError, match='velocity_deg_s must be > 0'):
            load_ur_params('ur10e')
        with pytest.raises(ConfigError, match='ur5e.yaml'):
            load_ur_params('ur5e')  # missing file
    finally:
        params_mod._load.cache_clear()


def test_frame_helpers_round_trip():
    rng = np.random.default_rng(3)
    for rpy in rng.uniform(-3, 3, (50, 3)) * [1, 0.5, 1]:
        rot = rpy_to_matrix(rpy)
        np.testing.assert_allclose(rpy_to_matrix(matrix_to_rpy(rot)), rot, atol=1e-12)
        w, x, y, z = quat_from_matrix(rot)
        # Rotation of a unit quaternion, written out independently.
        q_rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                          [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                          [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
        np.testing.assert_allclose(q_rot, rot, atol=1e-12)
    # URDF convention: fixed-axis roll, then pitch, then yaw.
    np.testing.assert_allclose(rpy_to_matrix((0, 0, math.pi / 2)) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(rpy_to_matrix((math.pi / 2, 0, math.pi / 2)) @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    with pytest.raises(ConfigError):
        Origin.from_matrix(np.diag([1.0, 1.0, -1.0, 1.0]))
