"""FollowJointTrajectory goal requests taken straight into arrays: same content as rclpy's conversion, over DDS."""
import ctypes
from contextlib import contextmanager

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from geometry_msgs.msg import Transform
from rclpy.action import CancelResponse, GoalResponse
from rclpy.node import Node
from ros_helpers import executor_with, ros_context, spin_until, spin_until_future
from trajectory_msgs.msg import JointTrajectoryPoint, MultiDOFJointTrajectoryPoint

from ur_common.action_client import ActionClient
from ur_sim_driver.gateway import goal_intake as intake_module
from ur_sim_driver.gateway.goal_intake import ArrayGoalActionServer, Request, _pointer, goal_intake, intake_error
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion.command_arrays import from_points

JOINTS = [f'joint_{i}' for i in range(6)]


def goal(count: int, ragged: bool = False) -> FollowJointTrajectory.Goal:
    g = FollowJointTrajectory.Goal()
    traj = g.trajectory
    traj.header.stamp.sec, traj.header.stamp.nanosec = 7, 125_000_000
    traj.header.frame_id = 'base_link'
    traj.joint_names = JOINTS
    rng = np.random.default_rng(count)
    for k in range(count):
        sizes = (6, 6, 0, 0) if not ragged or k % 3 else (6, k % 4, 2, 0)
        p = JointTrajectoryPoint(**{f: rng.normal(size=m).tolist() for f, m in
                                    zip(('positions', 'velocities', 'accelerations', 'effort'), sizes)})
        ns = 2_000_000 * (k + 1)
        p.time_from_start.sec, p.time_from_start.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
        traj.points.append(p)
    g.goal_tolerance = [JointTolerance(name='joint_1', position=0.05, velocity=-1.0)]
    g.path_tolerance = [JointTolerance(name='joint_2', position=0.2)]
    g.goal_time_tolerance.sec = 1
    return g


def expected_arrays(g):
    traj = g.trajectory
    return from_points(traj.joint_names, conv.time_to_sec(traj.header.stamp), traj.points)


def assert_same(got, want):
    assert got.joint_names == want.joint_names and got.header_stamp == want.header_stamp
    assert np.array_equal(got.times, want.times) and np.array_equal(got.sizes, want.sizes)
    for x, y in zip(got.values, want.values):
        assert np.array_equal(x, y)


def c_request(request):
    """`request` converted to a C message as rclpy does before sending; returns (address, destroy)."""
    meta = type(Request)
    create = ctypes.CFUNCTYPE(ctypes.c_void_p)(_pointer(meta._CREATE_ROS_MESSAGE))
    destroy = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(_pointer(meta._DESTROY_ROS_MESSAGE))
    from_py = ctypes.PYFUNCTYPE(ctypes.c_bool, ctypes.py_object, ctypes.c_void_p)(_pointer(meta._CONVERT_FROM_PY))
    address = create()
    assert from_py(request, address)
    return address, destroy


def test_the_intake_works_here():
    assert goal_intake() is not None, intake_error()
    assert intake_error() is None


@pytest.mark.parametrize('count, ragged', [(0, False), (1, False), (2000, False), (300, True)])
def test_split_gives_the_request_without_points_and_the_points_as_arrays(count, ragged):
    intake = goal_intake()
    request = Request()
    request.goal_id.uuid = list(range(16))
    request.goal = goal(count, ragged)
    point = MultiDOFJointTrajectoryPoint(transforms=[Transform()])
    request.goal.multi_dof_trajectory.points = [point]
    address, destroy = c_request(request)
    try:
        converted, arrays = intake.split(address)
    finally:
        destroy(address)
    assert converted.goal.trajectory.points == []
    assert_same(arrays, expected_arrays(request.goal))
    converted.goal.trajectory.points = request.goal.trajectory.points
    assert converted == request  # everything else as rclpy's own conversion gives it


class _Server:
    """An ArrayGoalActionServer recording what its callbacks got."""

    def __init__(self, node: Node) -> None:
        self.goals, self.arrays = [], []
        self.server = ArrayGoalActionServer(node, 'fjt', self._execute, goal_callback=self._on_goal,
                                            cancel_callback=lambda _: CancelResponse.ACCEPT)

    def _on_goal(self, g):
        self.goals.append(g)
        self.arrays.append(self.server.arrays_of(g))
        assert self.server.arrays_of(g) is None  # handed out once
        return GoalResponse.ACCEPT

    def _execute(self, handle):
        if handle.is_cancel_requested:
            handle.canceled()
        else:
            handle.succeed()
        return FollowJointTrajectory.Result(error_string=f'{len(handle.request.trajectory.points)} points')


@contextmanager
def _served():
    """(server, client, executor): the array-taking server and a plain client over DDS, the server ready."""
    with ros_context() as ctx:
        server_node, client_node = Node('intake_server', context=ctx), Node('intake_client', context=ctx)
        server = _Server(server_node)
        client = ActionClient(client_node, FollowJointTrajectory, 'fjt')
        with executor_with(ctx, server_node, client_node) as ex:
            spin_until(ex, client.server_is_ready, 10.0, 'the action server')
            yield server, client, ex


def test_goals_arrive_as_arrays_over_dds_and_end_as_usual():
    with _served() as (server, client, ex):
        for count in (20_000, 3):
            sent = goal(count)
            handle = spin_until_future(ex, client.send_goal_async(sent), 30.0, 'the goal response')
            assert handle.accepted
            result = spin_until_future(ex, handle.get_result_async(), 10.0, 'the result')
            assert result.status == GoalStatus.STATUS_SUCCEEDED
            assert result.result.error_string == '0 points'  # the goal handle's request has none
            got = server.goals[-1]
            assert got.trajectory.points == [] and list(got.trajectory.joint_names) == JOINTS
            assert got.goal_tolerance == sent.goal_tolerance and got.path_tolerance == sent.path_tolerance
            assert_same(server.arrays[-1], expected_arrays(sent))


def test_a_failed_read_falls_back_to_rclpys_conversion(monkeypatch):
    def broken(data):
        raise ValueError('broken on purpose')

    monkeypatch.setattr(intake_module, 'read_joint_trajectory', broken)
    with _served() as (server, client, ex):
        sent = goal(50)
        handle = spin_until_future(ex, client.send_goal_async(sent), 30.0, 'the goal response')
        assert handle.accepted
        result = spin_until_future(ex, handle.get_result_async(), 10.0, 'the result')
    assert result.result.error_string == '50 points'
    assert server.arrays == [None] and server.goals[0].trajectory == sent.trajectory
    assert 'broken on purpose' in goal_intake().failed
