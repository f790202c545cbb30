"""The driver's own scenarios of the controllers beside the joint controllers, each against a ur_sim started as that
test file's launch description starts the driver (powered off, headless, the dashboard client;
``sim_harness.driver_test_launch``) and the robot started by upstream's sequence before every test
(``sim_harness.start_robot``): tool_contact, force_mode and friction_model (ur_robot_driver/test at a16a268).
docs/upstream_tests.md maps each upstream test method to the tests that cover it."""
from __future__ import annotations

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from cm_helpers import BEST_EFFORT, STRICT, ControllerManagerClient
from control_msgs.action import FollowJointTrajectory
from rclpy.callback_groups import ReentrantCallbackGroup
from scipy.spatial.transform import Rotation
from sim_harness import driver_test_launch, point, ready_action, start_robot, wait_answer, wait_for, wait_still
from std_srvs.srv import Trigger
from ur_msgs.action import ToolContact
from ur_msgs.msg import FrictionModelParameters
from ur_msgs.srv import SetForceMode, SetFrictionModelParameters

from ur_common.action_client import ActionClient  # rclpy's loses a goal response that comes fast
from ur_sim_driver.robot.robot_state import NORMAL, POWER_OFF

pytestmark = pytest.mark.timeout(240)
SCALED, JTC, PASS = ('scaled_joint_trajectory_controller', 'joint_trajectory_controller',
                     'passthrough_trajectory_controller')
TOOL, FORCE, FRICTION = 'tool_contact_controller', 'force_mode_controller', 'friction_model_controller'
IDS = ['noprefix', 'my_ur_']


@pytest.fixture(scope='class')
def driver(request):
    """ur_sim as the driver's test launch description starts the driver, (tf_prefix, more ur_sim parameters) the
    class's parameter; the robot started once, so that each test is brought back to that."""
    prefix, params = getattr(request, 'param', ('', {}))
    with driver_test_launch(tf_prefix=prefix, **params) as h:
        assert h.sim.robot.robot_mode == POWER_OFF
        h.cm = ControllerManagerClient(h)
        h.prefix = prefix
        start_robot(h)
        h.keeper.remember()
        yield h


@pytest.fixture
def robot(driver):
    """Each test begins with the start sequence, as upstream's setUp does."""
    start_robot(driver)
    return driver


def call(h, srv_type, name: str, request):
    """One call of the service `name`; its response."""
    clients = h.services = getattr(h, 'services', {})
    if name not in clients:  # made once per ur_sim: it goes with the harness's node
        clients[name] = h.client.create_client(srv_type, name, callback_group=ReentrantCallbackGroup())
        wait_still(clients[name].service_is_ready, what=f'the service {name}')
    return wait_answer(clients[name].call_async(request), f'the answer of {name}')


# ---- integration_test_tool_contact.py ------------------------------------------------------------------------------
@pytest.mark.parametrize('driver', [('', {}), ('my_ur_', {})], indirect=True, ids=IDS)
class TestToolContact:
    def test_goals_inactive_busy_cancelled_and_aborted_by_deactivation(self, robot):
        h = robot
        client = getattr(h, 'tool_contact', None)
        if client is None:
            client = h.tool_contact = ActionClient(h.client, ToolContact, f'/{TOOL}/detect_tool_contact',
                                                   callback_group=ReentrantCallbackGroup())
            ready_action(client, probe_goals=False)  # an empty ToolContact goal is a real request

        def send():
            future = client.send_goal_async(ToolContact.Goal())
            wait_still(future.done, what='the ToolContact goal answer')
            return future.result()

        def status(handle) -> int:
            future = handle.get_result_async()
            wait_for(future.done, 10.0, 'the ToolContact result')
            return future.result().status

        assert h.cm.switch(deactivate=[TOOL], strictness=BEST_EFFORT).ok
        assert not send().accepted
        assert h.cm.switch(activate=[TOOL], strictness=BEST_EFFORT).ok
        first = send()
        assert first.accepted
        assert not send().accepted  # one goal at a time
        cancel = first.cancel_goal_async()
        wait_still(cancel.done, what='the cancel answer')
        assert cancel.result().return_code == 0
        assert status(first) == GoalStatus.STATUS_CANCELED
        second = send()
        assert second.accepted
        assert h.cm.switch(deactivate=[TOOL], strictness=BEST_EFFORT).ok
        assert status(second) == GoalStatus.STATUS_ABORTED


# ---- integration_test_force_mode.py --------------------------------------------------------------------------------
AWAY = [-1.6, -1.55, -1.7, -1.0, 2.05, 0.5]  # [rad] upstream's pose for force mode, in its joint order
UPSTREAM_ORDER = [2, 1, 0, 3, 4, 5]  # upstream's joint list (elbow first) in the controllers' order


def force_request(h, frame: str = 'base', quaternion=(0.0, 0.0, 0.0, 1.0), **fields) -> SetForceMode.Request:
    """A start_force_mode request in the frame `frame` (tf_prefix added) turned by `quaternion` (x, y, z, w)."""
    r = SetForceMode.Request(**fields)
    r.task_frame.header.frame_id = h.prefix + frame
    o = r.task_frame.pose.orientation
    o.x, o.y, o.z, o.w = quaternion
    return r


def tcp(h) -> tuple[np.ndarray, np.ndarray]:
    """The TCP (tool0_controller) position [m] and rotation (3, 3) in the base frame, as the robot has it now."""
    with h.sim.host.lock:
        position, quaternion = h.sim.sim.tcp_pose()
    return position.copy(), Rotation.from_quat(quaternion).as_matrix()


@pytest.mark.timeout(300)
@pytest.mark.parametrize('driver, beside_passthrough', [(('', {}), False), (('my_ur_', {}), True)], indirect=['driver'],
                         ids=['alone-noprefix', 'beside-passthrough-my_ur_'])
class TestForceMode:
    def test_ten_newtons_move_the_tcp_along_the_compliant_axis_only(self, robot, beside_passthrough):
        h = robot
        start, stop = f'/{FORCE}/start_force_mode', f'/{FORCE}/stop_force_mode'
        assert h.cm.switch(activate=[PASS], deactivate=[SCALED, JTC, FORCE], strictness=BEST_EFFORT).ok
        client = h.passthrough = getattr(h, 'passthrough', None) or _passthrough_client(h)
        away = np.array(AWAY)[UPSTREAM_ORDER]
        handle = h.send(h.goal([point(away, 5.0)]), client=client)
        assert handle.accepted and h.result(handle)[1] == 0
        deactivate = [SCALED, JTC] + ([] if beside_passthrough else [PASS])
        assert h.cm.switch(activate=[FORCE], deactivate=deactivate, strictness=BEST_EFFORT).ok
        p0, r0 = tcp(h)
        # The task frame: tool0_controller turned a quarter turn about its x axis, so that its z axis is the tool's -y.
        half = float(np.sqrt(0.5))
        request = force_request(h, 'tool0_controller', (half, 0.0, 0.0, half), selection_vector_z=True, type=2,
                                damping_factor=0.1, gain_scaling=0.8, deviation_limits=[1.0] * 6)
        request.wrench.force.z = 10.0
        request.speed_limits.linear.z = request.speed_limits.angular.z = 1.0
        assert call(h, SetForceMode, start, request).success
        h.wait_sim_time(5.0)
        p1, r1 = tcp(h)
        moved = r0.T @ (p1 - p0)  # in the tool's axes at the start
        assert moved[1] < -0.03, moved
        assert abs(moved[0]) < 1e-3 and abs(moved[2]) < 1e-3, moved
        assert np.degrees(Rotation.from_matrix(r0.T @ r1).magnitude()) < 0.1  # no turn
        assert call(h, Trigger, stop, Trigger.Request()).success
        assert h.cm.switch(deactivate=[FORCE]).ok
        assert h.sim.robot.safety_mode == NORMAL

    def test_refusals_and_the_limits_of_its_fields(self, robot, beside_passthrough):
        h = robot
        start, stop = f'/{FORCE}/start_force_mode', f'/{FORCE}/stop_force_mode'
        assert h.cm.switch(deactivate=[FORCE, SCALED, JTC], strictness=BEST_EFFORT).ok
        assert not call(h, SetForceMode, start, force_request(h)).success  # inactive
        assert h.cm.switch(activate=[FORCE], strictness=BEST_EFFORT).ok
        cases = [({'type': 0}, False), ({'type': 4}, False), ({'type': 1}, True), ({'type': 2}, True),
                 ({'type': 3}, True), ({'gain_scaling': -0.1}, False), ({'gain_scaling': 0.0}, True),
                 ({'gain_scaling': 2.0}, True), ({'gain_scaling': 2.1}, False), ({'damping_factor': -0.1}, False),
                 ({'damping_factor': 0.0}, True), ({'damping_factor': 1.0}, True), ({'damping_factor': 1.1}, False)]
        for fields, accepted in cases:
            assert call(h, SetForceMode, start, force_request(h, **fields)).success == accepted, fields
            if accepted:
                assert call(h, Trigger, stop, Trigger.Request()).success
        unknown = force_request(h)
        unknown.task_frame.header.frame_id = 'nonexisting6t54'
        assert not call(h, SetForceMode, start, unknown).success
        assert not call(h, SetForceMode, start, force_request(h, quaternion=(0.0, 0.0, 0.0, 0.0))).success

    def test_deactivating_the_controller_ends_force_mode_and_the_robot_holds(self, robot, beside_passthrough):
        h = robot
        assert h.cm.switch(activate=[FORCE], deactivate=[SCALED, JTC], strictness=BEST_EFFORT).ok
        request = force_request(h, selection_vector_z=True, type=2, damping_factor=0.1, gain_scaling=0.8,
                                deviation_limits=[1.0] * 6)
        request.wrench.force.z = 5.0
        request.speed_limits.linear.z = request.speed_limits.angular.z = 1.0
        assert call(h, SetForceMode, f'/{FORCE}/start_force_mode', request).success
        h.wait_sim_time(0.5)
        assert h.cm.switch(deactivate=[FORCE, SCALED, JTC], strictness=BEST_EFFORT).ok
        h.wait_sim_time(0.5)
        z = tcp(h)[0][2]
        h.wait_sim_time(0.5)
        assert abs(tcp(h)[0][2] - z) < 1e-6


def _passthrough_client(h) -> ActionClient:
    client = ActionClient(h.client, FollowJointTrajectory, f'/{PASS}/follow_joint_trajectory',
                          callback_group=ReentrantCallbackGroup())
    ready_action(client)
    return client


# ---- integration_test_friction_model.py ----------------------------------------------------------------------------
# URSim 'latest' runs a PolyScope 5 release that has the friction scales (5.25.1 or later), as ur_sim's UR5e does by
# default.
@pytest.mark.parametrize('driver', [('', {}), ('my_ur_', {})], indirect=True, ids=IDS)
class TestFrictionModel:
    def test_scales_are_set_on_the_robot_and_bad_lists_or_an_inactive_controller_refused(self, robot):
        h = robot
        name = f'/{FRICTION}/set_friction_model_parameters'
        controller = next(c for c in h.sim.components if c.name == FRICTION)

        def set_scales(viscous, coulomb) -> bool:
            request = SetFrictionModelParameters.Request(
                parameters=FrictionModelParameters(viscous_scale=viscous, coulomb_scale=coulomb))
            return call(h, SetFrictionModelParameters, name, request).success

        assert h.cm.switch(activate=[FRICTION], deactivate=[SCALED, JTC], strictness=BEST_EFFORT).ok
        viscous, coulomb = [0.9, 0.9, 0.8, 0.9, 0.9, 0.9], [0.8, 0.8, 0.7, 0.8, 0.8, 0.8]
        assert set_scales(viscous, coulomb)
        assert np.allclose(controller.scales[0], viscous) and np.allclose(controller.scales[1], coulomb)
        for bad in ((viscous[:5], coulomb), (viscous + [0.9], coulomb), (viscous, coulomb[:3])):
            assert not set_scales(*bad), bad
        assert np.allclose(controller.scales[0], viscous)  # nothing refused was kept
        assert h.cm.switch(deactivate=[FRICTION], strictness=STRICT).ok
        assert not set_scales(viscous, coulomb)
