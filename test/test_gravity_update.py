"""gravity_update_controller over DDS, and the gravity the robot's controller believes in: a vector that does not
match the mounting leaves gravity torques to the joint controller's feedback (the arm sags), the true one in any
frame of the robot does not; refusals name the field (the driver's GravityUpdateController and set_gravity)."""
from __future__ import annotations

import numpy as np
import pytest
from cm_helpers import STRICT, ControllerManagerClient
from geometry_msgs.msg import Vector3, Vector3Stamped
from sim_harness import point, running_sim, wait_answer, wait_still
from ur_msgs.srv import SetGravity

from ur_sim_driver.description.frames import frame_rotations, rotation_between
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import kinematic_tree

NAME = 'gravity_update_controller'
G = 9.81
# The upper arm and forearm stretched out: large gravity torques on shoulder and elbow.
STRETCHED = np.array([0.0, -0.6, 0.6, -1.57, 0.0, 0.0])


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:
        h.cm = ControllerManagerClient(h)
        h.gravity = h.client.create_client(SetGravity, f'/{NAME}/set_gravity')
        wait_still(h.gravity.service_is_ready, what='the set_gravity service')
        goal = h.send(h.goal([point(STRETCHED, 3.0, [0.0] * 6)]))
        assert goal.accepted and h.result(goal)[1] == 0
        h.keeper.remember()  # each test starts from the stretched arm
        yield h


def _set(h, vector, frame='base_link'):
    request = SetGravity.Request(gravity=Vector3Stamped(vector=Vector3(x=vector[0], y=vector[1], z=vector[2])))
    request.gravity.header.frame_id = frame
    return wait_answer(h.gravity.call_async(request), 'the set_gravity answer')


def _sag(h, held: np.ndarray, seconds: float = 1.0) -> float:
    """Largest joint deviation [rad] from `held` (where the robot holds), after `seconds` of simulated time."""
    h.wait_sim_time(seconds)
    return float(np.abs(h.q - held).max())


def test_active_by_default_and_kept_while_the_program_stops(robot):
    assert robot.cm.states()[NAME] == 'active'
    with robot.sim._lock:
        robot.sim.robot.pause()
    robot.wait_sim_time(0.1)
    assert robot.cm.states()[NAME] == 'active'  # one of the controller_stopper's consistent controllers


def test_a_wrong_gravity_makes_the_arm_sag_and_the_true_one_restores_it(robot):
    h = robot
    held = h.q.copy()
    assert _sag(h, held) < 1e-5
    tilted = G * np.array([0.0, np.sin(0.5), -np.cos(0.5)])  # 29 degrees off, in base_link
    try:
        answer = _set(h, tilted)
        assert (answer.success, answer.status) == (True, 'Gravity has been set successfully')
        assert _sag(h, held) > 1e-4  # about 3e-4 rad at the base joint: 26 N m the feedback must supply
    finally:
        assert _set(h, [0.0, 0.0, -G]).success
    assert _sag(h, held) < 1e-5


def test_the_true_gravity_given_in_the_tool_frame(robot):
    h = robot
    tree = kinematic_tree(h.sim.sim.params, '', get_tool('none'))
    rotations = frame_rotations(tree, h.q)
    in_tool0 = rotation_between(rotations, 'tool0', 'base_link') @ np.array([0.0, 0.0, -G])
    assert _set(h, in_tool0, 'tool0').success
    assert np.allclose(h.sim.sim.gravity_belief, [0.0, 0.0, G], atol=1e-9)  # anti-gravity in base
    held = h.q.copy()
    assert _sag(h, held) < 1e-5


def test_refusals(robot):
    h = robot
    unknown = _set(h, [0.0, 0.0, -G], 'world_frame')
    assert not unknown.success and "frame 'world_frame' does not exist; frames: base, base_link" in unknown.status
    assert not _set(h, [float('nan'), 0.0, -G]).success
    assert h.cm.switch(deactivate=[NAME], strictness=STRICT).ok
    try:
        inactive = _set(h, [0.0, 0.0, -G])
        assert (inactive.success, inactive.status) == (False, 'Controller is not active')
    finally:
        assert h.cm.switch(activate=[NAME], strictness=STRICT).ok
