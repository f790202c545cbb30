"""URScript functions that a controller knows only from a software version on (no ROS): optimovej and optimovel
(PolyScope 5.21), direct_torque (5.23) and its friction scales (5.25.1). An older controller does not know them, as
the robot's own does not: the program stops with the name it lacks."""
from __future__ import annotations

import numpy as np
import pytest
from script_box import READY, Box

from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.urscript.program import OPTIMOVEL_SPEED

pytestmark = pytest.mark.timeout(60)


def test_optimovej_moves_at_a_fraction_of_the_slowest_joints_limits():
    box = Box()
    target = [float(v) for v in np.add(READY, [0.8, 0.0, 0.0, 0.0, 0.0, 0.0])]
    box.run(f'''def prog():
  optimovej({target}, a=0.5, v=0.2)
end''')
    assert not box.errors(), box.errors()
    params = load_ur_params('ur5e')
    q = np.array(box.q)
    speed = np.abs(np.diff(q[:, 0])) / box.sim.control_dt
    assert np.allclose(q[-1], target, atol=1e-3)
    assert speed.max() == pytest.approx(0.2 * params.v_max.min(), rel=0.02)  # it cruises at the fraction


def test_optimovel_keeps_the_tool_on_a_line_at_a_fraction_of_the_tool_speed():
    box = Box()
    box.run('''def prog():
  start = get_actual_tcp_pose()
  optimovel(pose_add(start, p[0.0, 0.0, -0.2, 0, 0, 0]), a=0.5, v=0.1)
end''')
    assert not box.errors(), box.errors()
    tcp = np.array(box.tcp)
    drift = np.abs(tcp[:, :2] - tcp[0, :2]).max()
    speed = np.linalg.norm(np.diff(tcp, axis=0), axis=1) / box.sim.control_dt
    assert tcp[0, 2] - tcp[-1, 2] == pytest.approx(0.2, abs=1e-3) and drift < 5e-4
    assert speed.max() == pytest.approx(0.1 * OPTIMOVEL_SPEED, rel=0.05)  # measured: the arm follows closely


@pytest.mark.parametrize('call', ['optimovej(get_actual_joint_positions(), a=0, v=0.3)',
                                  'optimovel(get_actual_tcp_pose(), a=0.3, v=1.5)'])
def test_optimove_fractions_outside_zero_to_one_are_refused(call):
    box = Box()
    box.run(f'def prog():\n  {call}\nend')
    (error,) = box.errors()
    assert 'is a fraction in (0, 1]' in error.text and error.line == 2


@pytest.mark.parametrize('version, call, missing', [
    ('5.20.0', 'optimovej(get_actual_joint_positions())', "unknown function 'optimovej'"),
    ('5.20.0', 'optimovel(get_actual_tcp_pose())', "unknown function 'optimovel'"),
    ('5.22.0', 'direct_torque([0, 0, 0, 0, 0, 0])', "unknown function 'direct_torque'"),
    ('5.23.0', 'direct_torque([0, 0, 0, 0, 0, 0], viscous_scale=[0, 0, 0, 0, 0, 0])',
     "has no argument 'viscous_scale'"),
])
def test_an_older_controller_does_not_know_the_newer_functions(version, call, missing):
    box = Box(software_version=version)
    box.run(f'def prog():\n  {call}\nend')
    (error,) = box.errors()
    assert missing in error.text, error.text


def test_direct_torque_friction_scales_decide_how_much_friction_the_joint_feels():
    """0.5 N m on wrist_3 (Coulomb friction 0.56 N m): with the robot's full compensation it turns; with none the
    friction holds it; friction_comp=False is none."""
    speeds = {}
    for name, extra in (('full', ', viscous_scale=[1, 1, 1, 1, 1, 1], coulomb_scale=[1, 1, 1, 1, 1, 1]'),
                        ('none', ', viscous_scale=[0, 0, 0, 0, 0, 0], coulomb_scale=[0, 0, 0, 0, 0, 0]'),
                        ('off', ', friction_comp=False')):
        box = Box()
        box.run(f'''def prog():
  k = 0
  while k < 50:
    direct_torque([0, 0, 0, 0, 0, 0.5]{extra})
    k = k + 1
  end
  stopj(10)
end''')
        assert not box.errors(), box.errors()
        speeds[name] = np.abs(np.diff(np.array(box.q)[:52, 5])).max() / box.sim.control_dt
    assert speeds['full'] > 1.0 and speeds['none'] < 1e-3 and speeds['off'] < 1e-3, speeds


def test_direct_torque_friction_scales_are_fractions():
    box = Box()
    box.run('def prog():\n  direct_torque([0, 0, 0, 0, 0, 0], coulomb_scale=[0, 0, 0, 0, 0, 2])\nend')
    (error,) = box.errors()
    assert 'coulomb_scale is six numbers in [0, 1]' in error.text
