"""friction_model_controller over DDS: its service's refusals (inactive, list lengths, robot software older than
5.25.1) and the scales the robot keeps, clamped to [0, 1]; it runs beside every joint controller."""
from __future__ import annotations

import numpy as np
import pytest
from cm_helpers import STRICT, ControllerManagerClient
from sim_harness import running_sim, wait_answer, wait_still
from ur_msgs.msg import FrictionModelParameters
from ur_msgs.srv import SetFrictionModelParameters

NAME = 'friction_model_controller'
GOOD = dict(viscous_scale=[0.9, 0.9, 0.8, 0.9, 0.9, 0.9], coulomb_scale=[0.8, 0.8, 0.7, 0.8, 0.8, 1.5])


def _client(h):
    client = h.client.create_client(SetFrictionModelParameters, f'/{NAME}/set_friction_model_parameters')
    wait_still(client.service_is_ready, what='the friction model service')
    return client


def _set(h, client, **fields) -> bool:
    request = SetFrictionModelParameters.Request(parameters=FrictionModelParameters(**fields))
    return wait_answer(client.call_async(request), 'the friction model answer').success


def _component(h):
    return next(c for c in h.sim.components if c.name == NAME)


def test_older_robot_software_refuses():
    # First: its ur_sim shares the test process's domain, so it must be gone before the module's starts.
    with running_sim(software_version='5.12.6') as h:  # the client library's setFrictionScales needs 5.25.1
        assert not _set(h, _client(h), **GOOD)
        assert _component(h).scales is None


@pytest.fixture(scope='module')
def robot():
    with running_sim(software_version='5.25.1') as h:
        h.cm = ControllerManagerClient(h)
        h.friction = _client(h)
        yield h


def test_active_by_default_beside_the_joint_controllers(robot):
    states = robot.cm.states()
    assert states[NAME] == 'active' and states['scaled_joint_trajectory_controller'] == 'active'
    assert robot.cm.switch(activate=['passthrough_trajectory_controller'],
                           deactivate=['scaled_joint_trajectory_controller'], strictness=STRICT).ok
    assert robot.cm.states()[NAME] == 'active'


def test_scales_are_kept_clamped(robot):
    assert _set(robot, robot.friction, **GOOD)
    viscous, coulomb = _component(robot).scales
    assert np.allclose(viscous, GOOD['viscous_scale']) and coulomb[5] == 1.0 and coulomb[2] == 0.7


def test_refusals(robot):
    before = _component(robot).scales
    assert not _set(robot, robot.friction, viscous_scale=[0.5] * 5, coulomb_scale=[0.5] * 6)
    assert not _set(robot, robot.friction, viscous_scale=[0.5] * 6, coulomb_scale=[0.5] * 7)
    with robot.sim._lock:
        robot.sim.robot.stop()  # no External Control program: no script command socket
    assert not _set(robot, robot.friction, **GOOD)
    robot.keeper.recover()
    assert robot.cm.switch(deactivate=[NAME], strictness=STRICT).ok
    try:
        assert not _set(robot, robot.friction, **GOOD)  # inactive
    finally:
        assert robot.cm.switch(activate=[NAME], strictness=STRICT).ok
    assert _component(robot).scales is before  # nothing refused was kept

