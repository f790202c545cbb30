"""Frame orientations from the kinematic tree (description/frames.py) and the gravity torques of the physics."""
from __future__ import annotations

import numpy as np
import pytest

from ur_sim_driver.description.frames import frame_rotations, rotation_between
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import kinematic_tree


def test_base_is_base_link_turned_half_round():
    tree = kinematic_tree(load_ur_params('ur5e'), 'p_', get_tool('none'))
    rotations = frame_rotations(tree, np.zeros(6))
    r = rotation_between(rotations, 'p_base', 'p_base_link')
    assert np.allclose(r, np.diag([-1.0, -1.0, 1.0]))
    assert np.allclose(rotation_between(rotations, 'p_tool0', 'p_tool0'), np.eye(3))
    with pytest.raises(KeyError, match="frame 'tool0' does not exist; frames: p_base"):
        rotation_between(rotations, 'p_base', 'tool0')


def test_the_shoulder_turns_the_tool_about_base_z():
    tree = kinematic_tree(load_ur_params('ur5e'), '', get_tool('none'))
    q = np.array([0.0, -1.0, 1.2, -0.5, 0.7, 0.3])
    turned = q + np.array([0.4, 0, 0, 0, 0, 0])
    a = rotation_between(frame_rotations(tree, q), 'base', 'tool0')
    b = rotation_between(frame_rotations(tree, turned), 'base', 'tool0')
    c, s = np.cos(0.4), np.sin(0.4)
    assert np.allclose(b, np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ a)


def test_gravity_torques_equal_the_bias_at_rest():
    from ur_sim_driver.robot.sim_config import SimConfig
    from ur_sim_driver.robot.simulator import Simulator
    sim = Simulator(SimConfig(ur_type='ur10e', real_time_factor=0.0))
    for q in (np.array([0.0, -1.0, 1.0, -1.0, 0.5, 0.0]), np.array([1.0, -0.3, -1.2, 0.4, -1.0, 2.0])):
        sim.physics.reset(q)
        _, bias = sim.physics.dynamics()
        assert np.allclose(sim.physics.gravity_torques(sim.physics.gravity_in_base()), bias, atol=1e-9)
        assert np.allclose(sim.physics.gravity_torques(np.zeros(3)), 0.0)
