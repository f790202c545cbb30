"""The built interface packages work on the wire: one service of each over real DDS (private context)."""
from builtin_interfaces.msg import Duration
from rclpy.node import Node
from ros_helpers import executor_with, ros_context, spin_until, spin_until_future

TIMEOUT = 20.0  # [s] generous: discovery on a loaded 2-core CI machine


def _call(service_type, name, handler, request):
    """Serve `name` with `handler` and call it once with `request` from a second node; return the response."""
    with ros_context() as ctx:
        server_node = Node('iface_wire_server', context=ctx)
        client_node = Node('iface_wire_client', context=ctx)
        server_node.create_service(service_type, name, handler)
        client = client_node.create_client(service_type, name)
        with executor_with(ctx, server_node, client_node) as ex:
            spin_until(ex, client.service_is_ready, TIMEOUT, f'{name} discovery')
            return spin_until_future(ex, client.call_async(request), TIMEOUT, f'{name} response')


def test_ur_msgs_set_io_round_trip():
    from ur_msgs.srv import SetIO

    seen = []

    def handle(request, response):
        seen.append((request.fun, request.pin, request.state))
        response.success = request.fun == SetIO.Request.FUN_SET_DIGITAL_OUT
        return response

    request = SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=SetIO.Request.PIN_TOOL_DOUT1,
                            state=float(SetIO.Request.STATE_ON))
    response = _call(SetIO, 'iface_wire/set_io', handle, request)
    assert seen == [(1, 17, 1.0)]
    assert response.success is True


def test_ur_dashboard_msgs_get_robot_mode_round_trip():
    from ur_dashboard_msgs.msg import RobotMode
    from ur_dashboard_msgs.srv import GetRobotMode

    def handle(request, response):
        response.robot_mode.mode = RobotMode.POWER_OFF
        response.answer = 'Robotmode: POWER_OFF'
        response.success = True
        return response

    response = _call(GetRobotMode, 'iface_wire/get_robot_mode', handle, GetRobotMode.Request())
    assert (response.robot_mode.mode, response.answer, response.success) == (3, 'Robotmode: POWER_OFF', True)


def test_controller_manager_msgs_switch_controller_round_trip():
    from controller_manager_msgs.srv import SwitchController

    seen = []

    def handle(request, response):
        seen.append(request)
        response.ok = request.strictness == SwitchController.Request.STRICT
        response.message = f'activated {len(request.activate_controllers)}'
        return response

    request = SwitchController.Request(
        activate_controllers=['forward_position_controller'],
        deactivate_controllers=['scaled_joint_trajectory_controller'],
        strictness=SwitchController.Request.STRICT, activate_asap=True, timeout=Duration(sec=2, nanosec=500))
    response = _call(SwitchController, 'iface_wire/switch_controller', handle, request)
    assert (response.ok, response.message) == (True, 'activated 1')
    got = seen[0]
    assert list(got.activate_controllers) == ['forward_position_controller']
    assert list(got.deactivate_controllers) == ['scaled_joint_trajectory_controller']
    assert (got.strictness, got.activate_asap, got.timeout.sec, got.timeout.nanosec) == (2, True, 2, 500)


def test_tf2_msgs_frame_graph_round_trip():
    from tf2_msgs.srv import FrameGraph

    def handle(request, response):
        response.frame_yaml = 'tool0: {parent: flange}\n'
        return response

    response = _call(FrameGraph, 'iface_wire/tf2_frames', handle, FrameGraph.Request())
    assert response.frame_yaml == 'tool0: {parent: flange}\n'
