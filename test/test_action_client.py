"""ActionClient.wait_until_answering: it returns only once the server has answered, and the server sees no goal."""
import threading
import time

import pytest
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionServer, GoalResponse
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from ros_helpers import ros_context
from sim_harness import wait_still

from ur_glue_planner.execution.action_client import ActionClient
from ur_sim_driver.spin_thread import SpinThread

HELD = 0.3  # [s] the server's executor starts this late: the client must wait for its answers


def test_returns_after_the_server_answered_result_and_cancel_without_a_goal():
    with ros_context() as ctx:
        server_node, client_node = Node('probe_server', context=ctx), Node('probe_client', context=ctx)
        goals = []

        def on_goal(goal):
            goals.append(goal)
            return GoalResponse.REJECT
        ActionServer(server_node, FollowJointTrajectory, 'probe', lambda handle: None, goal_callback=on_goal)
        client = ActionClient(client_node, FollowJointTrajectory, 'probe')
        server_executor = SingleThreadedExecutor(context=ctx)
        server_executor.add_node(server_node)
        client_executor = SingleThreadedExecutor(context=ctx)
        client_executor.add_node(client_node)
        client_spinner = SpinThread(client_executor, 'probe_client').start()
        server_spinner = SpinThread(server_executor, 'probe_server')
        timer = threading.Timer(HELD, server_spinner.start)
        try:
            wait_still(client.server_is_ready, 10.0, 'discovery')  # readiness needs no spinning server
            start = time.monotonic()
            timer.start()
            client.wait_until_answering(timeout=10.0, resend=0.1)
            assert time.monotonic() - start >= HELD  # an answer, not the sending, ended the wait
            assert goals == []
        finally:
            timer.cancel()
            timer.join()
            client_spinner.stop()
            server_spinner.stop()
            client_node.destroy_node()
            server_node.destroy_node()


def test_no_server_is_a_timeout_naming_the_action_and_the_request():
    with ros_context() as ctx:
        node = Node('probe_alone', context=ctx)
        client = ActionClient(node, FollowJointTrajectory, '/nobody/follow_joint_trajectory')
        executor = SingleThreadedExecutor(context=ctx)
        executor.add_node(node)
        spinner = SpinThread(executor, 'probe_alone').start()
        try:
            with pytest.raises(TimeoutError, match=r'^/nobody/follow_joint_trajectory: the server answered none of '
                                                   r'[2-4] result requests within 0\.3 s$'):
                client.wait_until_answering(timeout=0.3, resend=0.1)
        finally:
            spinner.stop()
            node.destroy_node()
