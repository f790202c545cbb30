"""forward_effort_controller over DDS: refused on robot software older than 5.23.0; on 5.25.1 (the UR5e's default) it
starts only without another joint mode, its torques move the arm on top of the gravity compensation, the friction
model's scales change how the joints answer, no joint is driven past its speed limit, the safety system stops one
that could not stop before its position limit, and deactivated the robot holds."""
from __future__ import annotations

import numpy as np
import pytest
from cm_helpers import BEST_EFFORT, ControllerManagerClient
from sim_harness import point, running_sim, wait_answer, wait_for, wait_still
from std_msgs.msg import Float64MultiArray
from ur_msgs.msg import FrictionModelParameters
from ur_msgs.srv import SetFrictionModelParameters

from ur_sim_driver.robot.direct_torque import DEFAULT_COULOMB_SCALE, DEFAULT_VISCOUS_SCALE
from ur_sim_driver.robot.encoders import velocity_step
from ur_sim_driver.robot.robot_state import PROTECTIVE_STOP

SCALED, FEC = 'scaled_joint_trajectory_controller', 'forward_effort_controller'


def test_older_robot_software_refuses_torque_control():
    # First: its ur_sim shares the test process's domain, so it must be gone before the module's starts.
    with running_sim(software_version='5.12.6') as h:  # the hardware's words: test_controller_manager.py
        cm = ControllerManagerClient(h)
        response = cm.switch(activate=[FEC], deactivate=[SCALED])
        assert (response.ok, response.message) == (False, 'Could not switch controllers since prepare command mode '
                                                          'switch was rejected.')
        assert cm.states()[SCALED] == 'active' and cm.states()[FEC] == 'inactive'


@pytest.fixture(scope='module')
def robot():
    with running_sim() as h:  # ur5e: robot software 5.25.1, torque control and friction scales
        h.cm = ControllerManagerClient(h)
        h.pub = h.client.create_publisher(Float64MultiArray, f'/{FEC}/commands', 10)
        wait_still(lambda: h.pub.get_subscription_count() > 0, what='the commands subscriber')
        h.friction = h.client.create_client(SetFrictionModelParameters,
                                            '/friction_model_controller/set_friction_model_parameters')
        wait_still(h.friction.service_is_ready, what='the friction model service')
        h.effort = next(c for c in h.sim.components if c.name == FEC)
        yield h


@pytest.fixture(autouse=True)
def scaled_active(robot):
    robot.cm.switch(activate=[SCALED], deactivate=[FEC], strictness=BEST_EFFORT)
    try:
        yield
    finally:  # the robot back first (a test may end in a protective stop): the scales need its program running
        robot.keeper.recover()
        set_scales(robot, DEFAULT_VISCOUS_SCALE, DEFAULT_COULOMB_SCALE)


def set_scales(h, viscous, coulomb) -> None:
    request = SetFrictionModelParameters.Request(
        parameters=FrictionModelParameters(viscous_scale=list(viscous), coulomb_scale=list(coulomb)))
    assert wait_answer(h.friction.call_async(request), 'the friction model answer').success


def command(h, torques) -> None:
    """Publish joint torques and hold the simulation still until the controller has them."""
    values = np.asarray(torques, dtype=float)
    h.pub.publish(Float64MultiArray(data=list(values)))
    wait_still(lambda: h.effort._target is not None and np.array_equal(h.effort._target, values),
               what='the torques at the controller')


def wrist_3(torque: float) -> list[float]:
    return [0.0, 0.0, 0.0, 0.0, 0.0, torque]


def start_effort(h) -> None:
    assert h.cm.switch(activate=[FEC], deactivate=[SCALED]).ok


def test_effort_starts_only_without_another_joint_mode_and_holds_the_arm_until_commanded(robot):
    h = robot
    refused = h.cm.switch(activate=[FEC])  # beside the active position controller
    assert not refused.ok and h.cm.states()[FEC] == 'inactive'
    q0 = h.q.copy()
    start_effort(h)
    assert h.cm.states()[FEC] == 'active'
    h.wait_sim_time(1.0)  # no command yet: zero torques on top of the gravity compensation
    assert np.abs(h.q - q0).max() < 1e-4


def test_torques_move_the_arm_as_far_as_the_friction_compensation_lets_them(robot):
    h = robot
    start_effort(h)
    q0 = h.q.copy()
    set_scales(h, DEFAULT_VISCOUS_SCALE, [0.0] * 6)  # no Coulomb compensation: 0.56 N m holds wrist_3
    command(h, wrist_3(0.3))
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q0).max() < 1e-4
    set_scales(h, DEFAULT_VISCOUS_SCALE, DEFAULT_COULOMB_SCALE)  # 80 %: 0.11 N m left
    h.wait_sim_time(0.3)
    moved = h.q - q0
    assert moved[5] > 0.005 and np.abs(moved[:5]).max() < 1e-3
    # Deactivated: the torques are gone and the robot brakes as the driver's program does (stopj at 4 rad/s^2),
    # holding where it comes to rest.
    rec = h.record()  # a first recording steps the arm on until its subscription has matched: the speed after it
    speed = h.sim.sim.state().qd[5]
    assert h.cm.switch(deactivate=[FEC]).ok
    rest = round(0.1 / h.sim.sim.control_dt)  # 0.1 s of cycles reporting exactly 0: at rest, not passing through 0
    wait_for(lambda: len(rec.qd) > rest and not np.any(rec.qd[-rest:]), timeout=2.0 * speed / 4.0 + 0.3,
             what='the arm at rest (reported velocity exactly 0 for 0.1 s)')
    h.stop_recording()
    t, q, qd = rec.arrays()
    moving = np.flatnonzero(np.any(qd, axis=1))
    assert t[moving[-1]] - t[0] < speed / 4.0 + 0.1  # at rest within 0.1 s of stopj's time (4 rad/s^2)
    # No turning back: at most the settle of one encoder tick a period as the servo takes the arm to rest.
    assert qd[:, 5].min() >= -velocity_step(h.sim.sim.control_dt)
    q_held = h.q.copy()
    h.wait_sim_time(0.5)
    assert np.abs(h.q - q_held).max() < 1e-5


def test_a_joint_is_not_driven_past_its_speed_limit(robot):
    h = robot
    start_effort(h)
    rec = h.record()
    command(h, wrist_3(3.0))  # about 200 rad/s^2 on wrist_3: its speed limit within 20 ms
    h.wait_sim_time(0.3)
    command(h, wrist_3(-3.0))
    h.wait_sim_time(0.3)
    h.stop_recording()
    _, _, qd = rec.arrays()
    v_max = h.sim.sim.params.v_max[5]
    assert qd[:, 5].max() > 0.98 * v_max and np.abs(qd[:, 5]).max() <= v_max
    # Turned back at full torque and stopped before it runs into a limit (the robot's safety, if it must).
    assert h.cm.switch(deactivate=[FEC]).ok
    wait_for(lambda: np.abs(h.sim.sim.state().qd).max() < 1e-6, timeout=2.0, what='the arm at rest')


def test_a_joint_is_stopped_before_its_position_limit(robot):
    h = robot
    q_max = h.sim.sim.params.q_max[5]
    near = h.q.copy()
    near[5] = q_max - 0.3
    handle = h.send(h.goal([point(near, 4.0)]))
    assert handle.accepted and h.result(handle)[1] == 0
    start_effort(h)
    set_scales(h, [1.0] * 6, [1.0] * 6)  # no friction left: 0.05 N m accelerates wrist_3 at about 3 rad/s^2
    rec = h.record()
    command(h, wrist_3(0.05))
    wait_for(lambda: h.sim.robot.safety_mode == PROTECTIVE_STOP, timeout=3.0, what='the protective stop')
    h.wait_sim_time(1.0)
    h.stop_recording()
    _, q, _ = rec.arrays()
    assert q[:, 5].max() < q_max and q[:, 5].max() > near[5] + 0.1
    assert h.sim.robot.stop_cause.startswith('wrist_3_joint would pass its position limit')
    assert h.cm.states()[FEC] == 'inactive'  # the controller_stopper took it down
    # Braked and held where it came to rest, not turned back.
    step = np.diff(q[:, 5])
    assert step.min() > -1e-9
    assert np.abs(h.sim.sim.state().qd).max() < 1e-6
