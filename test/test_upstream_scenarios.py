"""The driver's own integration scenarios that need no motion, each against a ur_sim started as that test file's
launch description starts the driver: dashboard_client, launch_args, config_controller, controller_switch,
io_controller and component_lifecycle (ur_robot_driver/test at a16a268). The robot boots powered off,
as URSim does, and every scenario that upstream starts with its start sequence starts with ours
(``sim_harness.start_robot``). docs/upstream_tests.md maps each upstream test method to the tests that cover it."""
from __future__ import annotations

import json

import pytest
from builtin_interfaces.msg import Duration
from cm_helpers import BEST_EFFORT, STRICT, ControllerManagerClient
from geometry_msgs.msg import Vector3
from lifecycle_msgs.msg import State
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from ros_helpers import ros_context
from sim_harness import driver_test_launch, running_sim, start_robot, wait_answer, wait_for, wait_still
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import OperationalMode, RobotMode, SafetyStatus, UserRole
from ur_dashboard_msgs.srv import (
    DownloadProgram,
    GenerateFlightReport,
    GenerateSupportFile,
    GetOperationalMode,
    GetPolyScopeVersion,
    GetPrograms,
    GetRobotMode,
    GetRobotModel,
    GetSafetyStatus,
    GetSerialNumber,
    GetUserRole,
    IsInRemoteControl,
    SetOperationalMode,
    SetUserRole,
    UploadProgram,
)
from ur_msgs.msg import IOStates
from ur_msgs.srv import GetRobotSoftwareVersion, SetIO, SetPayload

from ur_sim_driver.robot.robot_state import IDLE, POWER_OFF, RUNNING
from ur_sim_driver.ros.node import UrSimNode

pytestmark = pytest.mark.timeout(240)
PREFIXES = ['', 'my_ur_']
SCALED, JTC = 'scaled_joint_trajectory_controller', 'joint_trajectory_controller'
FPC, FVC, FEC = 'forward_position_controller', 'forward_velocity_controller', 'forward_effort_controller'
PASS, FORCE, FREE = 'passthrough_trajectory_controller', 'force_mode_controller', 'freedrive_mode_controller'
TOOL, FRICTION = 'tool_contact_controller', 'friction_model_controller'
WRITERS = [SCALED, JTC, FPC, FVC, PASS, FORCE, FREE, FRICTION]  # every controller that commands the robot


@pytest.fixture(scope='class')
def driver(request):
    """ur_sim as the driver's test launch description starts the driver (its tf_prefix the class's parameter),
    with a controller manager client; the robot started once, so that each test is brought back to that."""
    with driver_test_launch(tf_prefix=getattr(request, 'param', '')) as h:
        h.cm = ControllerManagerClient(h)
        assert h.sim.robot.robot_mode == POWER_OFF and not h.sim.robot.program_running
        start_robot(h)
        h.keeper.remember()
        yield h


@pytest.fixture
def robot(driver):
    """Each test begins with the start sequence, as upstream's setUp does."""
    start_robot(driver)
    return driver


def call(h, srv_type, name: str, **fields):
    """Call the service `name` (absolute) once; its response."""
    clients = h.services = getattr(h, 'services', {})
    if name not in clients:  # made once per ur_sim: it goes with the harness's node
        clients[name] = h.client.create_client(srv_type, name, callback_group=ReentrantCallbackGroup())
        wait_still(clients[name].service_is_ready, what=f'the service {name}')
    return wait_answer(clients[name].call_async(srv_type.Request(**fields)), f'the answer of {name}')


# ---- dashboard_client.py: the dashboard client beside a robot of three software versions -------------------------
VERSIONS = [('ur30', '', False), ('ur15', '10.12.0', True), ('ur10', '3.15.8', True)]  # ur30's default: 5.25.1


@pytest.fixture(scope='class', params=VERSIONS, ids=['ur30-5.x', 'ur15-10.12.0', 'ur10-3.15.8'])
def dashboard(request):
    ur_type, version, autoconnect = request.param
    with running_sim(ros_args=['-p', f'dashboard_client:autoconnect:={str(autoconnect).lower()}'], ur_type=ur_type,
                     software_version=version, start_powered_off=True) as h:
        if not autoconnect:
            assert call(h, Trigger, '/dashboard_client/connect').success
        yield h


def dash(h, srv_type, name: str, **fields):
    return call(h, srv_type, f'/dashboard_client/{name}', **fields)


class TestDashboardClient:
    def test_power_on_and_brake_release_from_power_off(self, dashboard):
        h = dashboard
        version = h.sim.cfg.software_version
        if version.major == 5 or dash(h, IsInRemoteControl, 'is_in_remote_control').remote_control:
            assert dash(h, Trigger, 'power_off').success
        assert dash(h, GetRobotMode, 'get_robot_mode').robot_mode.mode == RobotMode.POWER_OFF
        assert dash(h, Trigger, 'power_on').success
        wait_for(lambda: h.sim.robot.robot_mode in (IDLE, RUNNING), 10.0, 'the robot powered on')
        assert dash(h, GetRobotMode, 'get_robot_mode').robot_mode.mode in (RobotMode.IDLE, RobotMode.RUNNING)
        assert dash(h, Trigger, 'brake_release').success
        wait_for(lambda: h.sim.robot.robot_mode == RUNNING, 10.0, 'the brakes released')
        assert dash(h, GetRobotMode, 'get_robot_mode').robot_mode.mode == RobotMode.RUNNING

    def test_what_the_version_offers(self, dashboard, tmp_path):
        h = dashboard
        version = h.sim.cfg.software_version
        if version.major == 10:  # PolyScope X: programs are files of the robot; no version, serial or reports
            assert not dash(h, GetPolyScopeVersion, 'get_polyscope_version').success
            assert dash(h, GetOperationalMode, 'get_operational_mode').operational_mode.mode in ('MANUAL',
                                                                                                 'AUTOMATIC')
            source = tmp_path / 'ours.urpx'
            source.write_text(json.dumps({'program': {'programInformation': {'name': 'ours uploaded'}}}))
            r = dash(h, UploadProgram, 'upload_program', file_path=str(source))
            assert r.success and r.program_name == 'ours uploaded'
            assert 'ours uploaded' in [p.name for p in dash(h, GetPrograms, 'get_programs').programs]
            target = tmp_path / 'back.urpx'
            assert dash(h, DownloadProgram, 'download_program', program_name='ours uploaded',
                        target_path=str(target)).success
            assert json.loads(target.read_text()) == json.loads(source.read_text())
            return
        r = dash(h, GetPolyScopeVersion, 'get_polyscope_version')
        assert r.success and (r.version.major, r.version.minor) == (version.major, version.minor)
        r = dash(h, GetSerialNumber, 'get_serial_number')
        assert r.success and r.serial_number > 0
        r = dash(h, GetRobotModel, 'get_robot_model')
        assert r.success and r.robot_model == h.sim.cfg.ur_type.upper()
        r = dash(h, GenerateFlightReport, 'generate_flight_report')
        assert r.success and (h.sim.host.robot_files / 'flightreports' / f'{r.report_id}.json').is_file()
        r = dash(h, GenerateSupportFile, 'generate_support_file')
        assert r.success and (h.sim.host.robot_files / r.generated_file_name).is_file()
        if version.major == 3:  # CB3: user roles, no operational mode or safety status
            assert not dash(h, GetSafetyStatus, 'get_safety_status').success
            try:
                for role in (UserRole.PROGRAMMER, UserRole.OPERATOR, UserRole.NONE, UserRole.LOCKED,
                             UserRole.RESTRICTED):
                    assert dash(h, SetUserRole, 'set_user_role', user_role=UserRole(role=role)).success
                    assert dash(h, GetUserRole, 'get_user_role').user_role.role == role
            finally:
                assert dash(h, SetUserRole, 'set_user_role', user_role=UserRole(role=UserRole.PROGRAMMER)).success
            return
        assert dash(h, GetSafetyStatus, 'get_safety_status').safety_status.status == SafetyStatus.NORMAL
        assert not dash(h, GetUserRole, 'get_user_role').success  # e-Series: no user roles
        try:
            for mode in (OperationalMode.MANUAL, OperationalMode.AUTOMATIC):
                assert dash(h, SetOperationalMode, 'set_operational_mode',
                            operational_mode=OperationalMode(mode=mode)).success
                assert dash(h, GetOperationalMode, 'get_operational_mode').operational_mode.mode == mode
        finally:
            assert dash(h, Trigger, 'clear_operational_mode').success
        assert dash(h, IsInRemoteControl, 'is_in_remote_control').remote_control


# ---- launch_args.py: launch_dashboard_client ----------------------------------------------------------------------
@pytest.mark.parametrize('launch_dashboard_client', [True, False])
def test_the_dashboard_client_node_exists_as_launched(launch_dashboard_client):
    """The driver's launch description with launch_dashboard_client true or false: the node /dashboard_client is in
    the ROS graph, or is not, once the controller manager is (upstream waits for its services)."""
    with ros_context() as ctx:
        sim = UrSimNode(context=ctx, start=False, parameter_overrides=_overrides(
            headless_mode=True, start_powered_off=True, launch_dashboard_client=launch_dashboard_client))
        observer = Node('launch_args_observer', context=ctx)
        try:
            def nodes() -> set[str]:
                return {ns.rstrip('/') + '/' + name for name, ns in observer.get_node_names_and_namespaces()}
            wait_still(lambda: '/controller_manager' in nodes() and '/io_and_status_controller' in nodes(),
                       what='the controller manager in the graph')
            assert ('/dashboard_client' in nodes()) == launch_dashboard_client
            assert sim.robot.robot_mode == POWER_OFF  # nothing has started it
        finally:
            observer.destroy_node()
            sim.shutdown()
            sim.destroy_node()


def _overrides(**params):
    ports = {f'{name}.port': 0 for name in ('dashboard_server', 'rtde', 'primary', 'secondary', 'realtime')}
    return [Parameter(name, value=value) for name, value in {**ports, **params}.items()]


# ---- integration_test_config_controller.py -------------------------------------------------------------------------
@pytest.mark.parametrize('driver', PREFIXES, indirect=True, ids=['noprefix', 'my_ur_'])
class TestConfigController:
    def test_the_robot_software_version_is_the_robots(self, robot):
        r = call(robot, GetRobotSoftwareVersion, '/ur_configuration_controller/get_robot_software_version')
        assert (r.major, r.minor, r.bugfix, r.build) == tuple(robot.sim.cfg.software_version)
        assert r.major > 1


# ---- integration_test_controller_switch.py -------------------------------------------------------------------------
# Sets of controllers that cannot be active together (they claim the same joints, or modes the robot cannot combine),
# and sets that can, each started from no commanding controller active.
CONFLICTS = [(SCALED, JTC), (SCALED, FPC), (SCALED, FVC), (SCALED, PASS), (FVC, PASS), (FPC, FVC), (SCALED, FORCE),
             (SCALED, FREE), (FORCE, TOOL), (TOOL, FREE)]
COMPATIBLE = [(PASS, FORCE), (SCALED, TOOL), (PASS, TOOL), (SCALED, FRICTION), (PASS, FRICTION),
              (PASS, FORCE, FRICTION)]


@pytest.mark.parametrize('driver', PREFIXES, indirect=True, ids=['noprefix', 'my_ur_'])
class TestControllerSwitch:
    def test_conflicting_controllers_never_start_together(self, robot):
        cm = robot.cm
        assert cm.switch(deactivate=WRITERS, strictness=BEST_EFFORT).ok
        for group in CONFLICTS:
            assert not cm.switch(activate=group).ok, group
            assert not {name for name, state in cm.states().items() if state == 'active'} & set(group), group

    def test_compatible_controllers_start_and_stop_together(self, robot):
        cm = robot.cm
        assert cm.switch(deactivate=WRITERS, strictness=BEST_EFFORT).ok
        for group in COMPATIBLE:
            assert cm.switch(activate=group).ok, group
            assert all(cm.states()[name] == 'active' for name in group), group
            assert cm.switch(deactivate=group).ok, group

    @pytest.mark.parametrize('holder', [SCALED, PASS])
    def test_a_running_joint_controller_keeps_the_others_out(self, robot, holder):
        cm = robot.cm
        assert cm.switch(activate=[holder], deactivate=[c for c in WRITERS if c != holder],
                         strictness=BEST_EFFORT).ok
        others = [SCALED, JTC, FPC, FVC, FEC, FREE, PASS] + ([FORCE] if holder == SCALED else [])
        for other in others:
            if other != holder:
                assert not cm.switch(activate=[other], strictness=STRICT).ok, other
        assert cm.switch(deactivate=[holder]).ok
        if holder == PASS:  # force mode runs beside the passthrough controller, either started first
            assert cm.switch(activate=[FORCE]).ok and cm.switch(activate=[PASS]).ok


# ---- integration_test_io_controller.py -----------------------------------------------------------------------------
class TestIoController:
    def test_a_digital_output_set_and_cleared_is_published(self, robot):
        h = robot
        seen: list[bool] = []
        stop = h.listen(IOStates, '/io_and_status_controller/io_states',
                        lambda msg: seen.append(msg.digital_out_states[0].state))
        try:
            for state in (1.0, 0.0):
                before = len(seen)
                r = call(h, SetIO, '/io_and_status_controller/set_io', fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=0,
                         state=state)
                assert r.success
                wait_for(lambda b=before, v=bool(state): len(seen) > b and seen[-1] == v, 5.0,
                         f'digital out 0 at {state}')
        finally:
            stop()

    def test_payloads_set_one_after_another_are_the_robots(self, robot):
        h = robot
        payloads = [(1.5, (0.01, 0.02, 0.03), (0.0,) * 6, 0), (0.0, (0.0,) * 3, (0.0,) * 6, 0),
                    (1.0, (0.1, 0.0, 0.2), (0.01, 0.01, 0.02, 0.0, 0.0, 0.0), 0),
                    (1.0, (0.0, 0.0, 0.1), (0.01, 0.01, 0.02, 0.0, 0.0, 0.0), 1),  # 1 s transition
                    (2.0, (0.05, 0.05, 0.15), (0.02, 0.02, 0.04, 0.0, 0.0, 0.0), 0),
                    (0.0, (0.0,) * 3, (0.0,) * 6, 0)]
        for mass, cog, inertia, seconds in payloads:
            ixx, iyy, izz, ixy, ixz, iyz = inertia
            answer = call(h, SetPayload, '/io_and_status_controller/set_payload', mass=mass,
                          center_of_gravity=Vector3(x=cog[0], y=cog[1], z=cog[2]), ixx=ixx, iyy=iyy, izz=izz,
                          ixy=ixy, ixz=ixz, iyz=iyz, transition_time=Duration(sec=seconds))
            assert answer.success, mass
            payload = h.sim.sim.payload
            assert payload.mass == pytest.approx(mass) and tuple(payload.cog) == pytest.approx(cog), mass


# ---- integration_test_component_lifecycle.py -----------------------------------------------------------------------
class TestComponentLifecycle:
    def test_the_component_through_inactive_unconfigured_and_back(self, robot):
        cm = robot.cm
        steps = [(None, State.PRIMARY_STATE_ACTIVE, True), (State.PRIMARY_STATE_INACTIVE, State.PRIMARY_STATE_INACTIVE,
                                                             True),
                 (State.PRIMARY_STATE_UNCONFIGURED, State.PRIMARY_STATE_UNCONFIGURED, False),
                 (State.PRIMARY_STATE_ACTIVE, State.PRIMARY_STATE_ACTIVE, True)]
        for target, state, available in steps:
            if target is not None:
                assert cm.set_component_state('ur5e', target).ok, target
            (component,) = cm.components()
            assert (component.name, component.state.id) == ('ur5e', state)
            interfaces = [*component.command_interfaces, *component.state_interfaces]
            assert interfaces and all(i.is_available == available for i in interfaces), state
        assert not robot.sim.robot.program_running  # the driver was disconnected: its program had ended
