"""Smoke tests of the ROS environment: real DDS, private contexts, the built control_msgs."""
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from rclpy.action import ActionServer
from rclpy.node import Node
from ros_helpers import executor_with, ros_context, spin_until, spin_until_future
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectoryPoint

from ur_common.action_client import ActionClient

TIMEOUT = 20.0  # [s] generous: discovery on a loaded 2-core CI machine


def test_joint_state_round_trip():
    received = []
    with ros_context() as ctx:
        pub_node = Node('smoke_pub', context=ctx)
        sub_node = Node('smoke_sub', context=ctx)
        pub = pub_node.create_publisher(JointState, 'smoke_joint_states', 10)
        sub_node.create_subscription(JointState, 'smoke_joint_states', received.append, 10)
        with executor_with(ctx, pub_node, sub_node) as ex:
            spin_until(ex, lambda: pub.get_subscription_count() > 0, TIMEOUT, 'subscriber discovery')
            msg = JointState(name=['a', 'b'], position=[0.5, -1.25], velocity=[0.0, 2.0], effort=[1.0, 3.0])
            msg.header.stamp.sec = 42
            pub.publish(msg)
            spin_until(ex, lambda: received, TIMEOUT, 'the JointState message')
    got = received[0]
    assert list(got.name) == ['a', 'b']
    assert list(got.position) == [0.5, -1.25]
    assert list(got.effort) == [1.0, 3.0]
    assert got.header.stamp.sec == 42


def test_follow_joint_trajectory_goal_feedback_result():
    """An in-test action server echoes the goal back through feedback and result."""
    seen_goals = []
    feedbacks = []

    def execute(goal_handle):
        goal = goal_handle.request
        seen_goals.append(goal)
        fb = FollowJointTrajectory.Feedback()
        fb.joint_names = list(goal.trajectory.joint_names)
        fb.desired = goal.trajectory.points[-1]
        goal_handle.publish_feedback(fb)
        goal_handle.succeed()
        result = FollowJointTrajectory.Result()
        result.error_code = FollowJointTrajectory.Result.GOAL_TOLERANCE_VIOLATED
        result.error_string = f'{len(goal.trajectory.points)} points, tol {goal.goal_tolerance[0].position}'
        return result

    with ros_context() as ctx:
        server_node = Node('smoke_fjt_server', context=ctx)
        client_node = Node('smoke_fjt_client', context=ctx)
        ActionServer(server_node, FollowJointTrajectory, 'smoke/follow_joint_trajectory', execute)
        client = ActionClient(client_node, FollowJointTrajectory, 'smoke/follow_joint_trajectory')
        with executor_with(ctx, server_node, client_node) as ex:
            spin_until(ex, client.server_is_ready, TIMEOUT, 'action server discovery')
            goal = FollowJointTrajectory.Goal()
            goal.trajectory.joint_names = ['j1', 'j2']
            goal.trajectory.points = [
                JointTrajectoryPoint(positions=[0.1, 0.2], time_from_start=Duration(sec=1)),
                JointTrajectoryPoint(positions=[0.3, 0.4], time_from_start=Duration(sec=2)),
            ]
            goal.goal_tolerance = [JointTolerance(name='j1', position=0.05)]
            goal.goal_time_tolerance = Duration(nanosec=10_000_000)
            handle = spin_until_future(ex, client.send_goal_async(goal, feedback_callback=feedbacks.append),
                                       TIMEOUT, 'goal acceptance')
            assert handle.accepted
            result = spin_until_future(ex, handle.get_result_async(), TIMEOUT, 'the result')
            spin_until(ex, lambda: feedbacks, TIMEOUT, 'feedback')
    assert result.result.error_code == -5
    assert result.result.error_string == '2 points, tol 0.05'
    assert seen_goals[0].goal_time_tolerance.nanosec == 10_000_000
    assert feedbacks and list(feedbacks[0].feedback.desired.positions) == [0.3, 0.4]
