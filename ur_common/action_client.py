"""rclpy's ActionClient without its lost-response race (ros2/rclpy#1123).

rclpy 7.1.6 (the Jazzy wheel on PyPI) sends a goal, cancel or result request and only then registers the
future that its response completes. When another thread spins the client's executor, as in every script
that calls ``send_goal_async`` while a background executor runs, the response can be taken in between: rclpy
logs "Ignoring unexpected ... response" and the future never completes (a goal that is never answered, a
result never delivered). Upstream fixed it later (rclpy PRs #1308, #1517, #1519) with a lock; no wheel on PyPI
has the fix yet. This subclass does the same: sending and registering happen under a lock, and the executor
takes responses under it too, so a response is always taken after its future exists.

rclpy also updates its table of goal handles in ``execute`` without a lock: when two threads execute the client's
data at once (a reentrant callback group on a multi-threaded executor), both can find a finished goal in a status
message and both delete it; the second raises KeyError in the executor and the rest of that status message (other
goals' states) is lost. Here ``execute`` runs under a lock too.

A second loss is DDS's: a server drops a response it sends before its response writer has matched the client's
response reader (rmw_fastrtps waits 100 ms for the match, then logs "client will not receive response").
``server_is_ready`` proves only the other direction. ``wait_until_answering`` closes that gap for the result and
cancel services, with requests about a goal the server never had: they change nothing on the server.
"""
from __future__ import annotations

import threading
import time
import uuid

from rclpy.action import ActionClient as _RclpyActionClient
from rclpy.action.client import ClientGoalHandle
from unique_identifier_msgs.msg import UUID

POLL = 0.002  # [s] between looks at the pending answers


class ActionClient(_RclpyActionClient):
    """Drop-in replacement for ``rclpy.action.ActionClient`` (same arguments)."""

    def __init__(self, *args, **kwargs) -> None:
        self._request_lock = threading.RLock()
        self._execute_lock = threading.Lock()
        super().__init__(*args, **kwargs)

    def send_goal_async(self, goal, feedback_callback=None, goal_uuid=None):
        with self._request_lock:
            return super().send_goal_async(goal, feedback_callback, goal_uuid)

    def _cancel_goal_async(self, goal_handle):
        with self._request_lock:
            return super()._cancel_goal_async(goal_handle)

    def _get_result_async(self, goal_handle):
        with self._request_lock:
            return super()._get_result_async(goal_handle)

    def take_data(self):
        with self._request_lock:
            return super().take_data()

    async def execute(self, taken_data):
        # rclpy's execute awaits only a feedback callback: a coroutine callback must not wait for this client's data
        with self._execute_lock:
            await super().execute(taken_data)

    def wait_until_answering(self, timeout: float = 10.0, resend: float = 1.0) -> None:
        """Block until the server has answered a result request and a cancel request of this client.

        Call after ``server_is_ready``, with the client's executor spinning in another thread. Both requests name a
        random goal id the server never had (answers: status UNKNOWN, cancel ERROR_UNKNOWN_GOAL_ID) and are sent
        again every `resend` [s] of wall time until each is answered once.

        Raises:
            TimeoutError: no answer to one of them within `timeout` [s] of wall time, naming the action.
        """
        ghost = ClientGoalHandle(self, UUID(uuid=list(uuid.uuid4().bytes)), None)
        probes = {'result': self._get_result_async, 'cancel': self._cancel_goal_async}
        deadline = time.monotonic() + timeout
        for what, send in probes.items():
            futures = []
            while not any(f.done() for f in futures):
                if time.monotonic() > deadline:
                    raise TimeoutError(f'{self._action_name}: the server answered none of {len(futures)} {what} '
                                       f'requests within {timeout:.1f} s')
                futures.append(send(ghost))
                again = min(time.monotonic() + resend, deadline)
                while time.monotonic() < again and not any(f.done() for f in futures):
                    time.sleep(POLL)
            for f in futures:
                if not f.done():
                    f.cancel()
