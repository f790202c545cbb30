"""Our ActionClient: wait_until_answering returns only once the server has answered (and the server sees no goal);
two threads executing the client's data at once update its goal table once."""
import threading
import time
import weakref

import pytest
from action_msgs.msg import GoalInfo, GoalStatus, GoalStatusArray
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionServer, GoalResponse
from rclpy.action.client import ClientGoalHandle
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from ros_helpers import ros_context
from sim_harness import wait_still
from unique_identifier_msgs.msg import UUID

from ur_common.action_client import ActionClient
from ur_common.spin_thread import SpinThread

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


class _MeetingHandle(ClientGoalHandle):
    """A goal handle whose status update waits (at most MEET s) for a second thread to update it too: the
    interleaving in which rclpy's unlocked execute deletes a finished goal twice."""

    def __init__(self, *args) -> None:
        self.meeting: threading.Barrier | None = None
        super().__init__(*args)

    @property
    def _status(self):
        return self._value

    @_status.setter
    def _status(self, value) -> None:
        self._value = value
        if self.meeting is not None:
            try:
                self.meeting.wait(MEET)
            except threading.BrokenBarrierError:
                pass  # the other thread is held by the client's lock: go on alone


MEET = 1.0  # [s] the longest a status update waits for the other thread's


def _run(coroutine) -> None:
    """Drive a coroutine that never suspends, as rclpy's executor does."""
    try:
        coroutine.send(None)
    except StopIteration:
        return
    raise AssertionError('execute suspended')


def test_two_threads_executing_one_finished_status_update_the_table_once():
    with ros_context() as ctx:
        node = Node('execute_twice', context=ctx)
        client = ActionClient(node, FollowJointTrajectory, 'execute_twice')
        goal_id = UUID(uuid=list(range(16)))
        handle = _MeetingHandle(client, goal_id, FollowJointTrajectory.Impl.SendGoalService.Response(accepted=True))
        client._goal_handles[bytes(goal_id.uuid)] = weakref.ref(handle)
        handle.meeting = threading.Barrier(2)
        done = GoalStatusArray(status_list=[GoalStatus(goal_info=GoalInfo(goal_id=goal_id),
                                                       status=GoalStatus.STATUS_SUCCEEDED)])
        errors = []

        def execute() -> None:
            try:
                _run(client.execute({'status': done}))
            except Exception as exc:  # noqa: BLE001 -- what the executor thread would die of
                errors.append(exc)
        threads = [threading.Thread(target=execute) for _ in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=10.0)
        try:
            assert errors == []
            assert handle.status == GoalStatus.STATUS_SUCCEEDED
            assert client._goal_handles == {}
        finally:
            client.destroy()
            node.destroy_node()
