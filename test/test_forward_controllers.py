"""forward_position_controller and forward_velocity_controller over DDS: refused while inactive, moving the arm
within the robot's limits when active, bad commands refused."""
from __future__ import annotations

import numpy as np
import pytest
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from sim_harness import running_sim, wait_for, wait_still
from std_msgs.msg import Float64MultiArray

from ur_sim_driver.controllers.forward_command import check_command

SCALED = 'scaled_joint_trajectory_controller'
FPC, FVC = 'forward_position_controller', 'forward_velocity_controller'


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.cm = ControllerManagerClient(h)
        h.pub = {name: h.client.create_publisher(Float64MultiArray, f'/{name}/commands', 10) for name in (FPC, FVC)}
        for pub in h.pub.values():
            wait_still(lambda pub=pub: pub.get_subscription_count() > 0, what='the commands subscriber')
        yield h


@pytest.fixture(autouse=True)
def scaled_active(robot):
    robot.cm.switch(activate=[SCALED], deactivate=[FPC, FVC], strictness=BEST_EFFORT)


def _send(h, name, values) -> None:
    h.pub[name].publish(Float64MultiArray(data=[float(v) for v in values]))


def test_commands_are_refused_while_inactive(robot):
    h = robot
    q0 = h.q
    _send(h, FPC, q0 + 0.2)
    _send(h, FVC, [0.5] * 6)
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q0).max() < 1e-3
    # Activation starts from no command: the old message is not replayed.
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q0).max() < 1e-3


def test_position_commands_move_the_arm_within_its_limits(robot):
    h = robot
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    target = h.q + np.array([0.6, -0.3, 0.3, 0.0, 0.2, 0.0])
    rec = h.record()
    _send(h, FPC, target)
    wait_for(lambda: np.abs(h.q - target).max() < 1e-3, what='the arm at the commanded position')
    h.wait_sim_time(0.3)
    h.stop_recording()
    _, _, qd = rec.arrays()
    v_max = h.sim.sim.params.v_max
    assert (np.abs(qd) <= v_max * 1.02).all()
    assert np.abs(h.q - target).max() < 1e-3  # it stays there


def test_velocity_commands_move_the_arm_within_its_limits(robot):
    h = robot
    assert h.cm.switch(activate=[FVC], deactivate=[SCALED]).ok
    rec = h.record()
    _send(h, FVC, [0.4, 0, 0, 0, 0, 0])
    h.wait_sim_time(1.0)
    _, _, qd = rec.arrays()
    assert abs(qd[-1, 0] - 0.4) < 0.01 and np.abs(qd[-1, 1:]).max() < 0.01
    # Far above the limit: the joint moves at its limit, no faster.
    _send(h, FVC, [0, 0, 0, 0, 0, 50.0])
    h.wait_sim_time(1.5)
    _send(h, FVC, [0.0] * 6)
    h.wait_sim_time(1.5)
    h.stop_recording()
    _, _, qd = rec.arrays()
    v_max = h.sim.sim.params.v_max
    assert np.abs(qd[:, 5]).max() > 0.9 * v_max[5] and (np.abs(qd) <= v_max * 1.02).all()
    assert np.abs(h.sim.sim.state().qd).max() < 1e-3  # stopped on the zero command


def test_bad_commands_are_refused_with_the_reason(robot, capfd):
    h = robot
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    q0 = h.q
    _send(h, FPC, q0[:5] + 0.3)
    _send(h, FPC, [float('nan')] + list(q0[1:] + 0.3))
    h.wait_sim_time(1.0)
    assert np.abs(h.q - q0).max() < 1e-3
    wait_for(lambda: 'command size (5) does not match number of interfaces (6)' in capfd.readouterr().err,
             what='the size to be logged')


def test_only_one_joint_command_controller_at_a_time(robot):
    h = robot
    assert h.cm.switch(activate=[FPC], deactivate=[SCALED]).ok
    assert not h.cm.switch(activate=[FVC]).ok  # velocity with position: the hardware refuses
    assert not h.cm.switch(activate=[SCALED]).ok  # the same position interfaces
    assert h.cm.switch(activate=[FVC], deactivate=[FPC]).ok


def test_check_command():
    joints = tuple('abcdef')
    assert check_command([0.0] * 6, joints) is None
    assert check_command([0.0] * 7, joints) == 'command size (7) does not match number of interfaces (6)'
    assert 'command for c is inf' in check_command([0, 0, float('inf'), 0, 0, 0], joints)
