"""rclpy's ActionClient without its lost-response race (ros2/rclpy#1123).

rclpy 7.1.6 (the Jazzy wheel on PyPI) sends a goal, cancel or result request and only then registers the
future that its response completes. When another thread spins the client's executor, as in every script
that calls ``send_goal_async`` while a background executor runs, the response can be taken in between: rclpy
logs "Ignoring unexpected ... response" and the future never completes (a goal that is never answered, a
result never delivered). Upstream fixed it later (rclpy PRs #1308, #1517, #1519) with a lock; no wheel on PyPI
has the fix yet. This subclass does the same: sending and registering happen under a lock, and the executor
takes responses under it too, so a response is always taken after its future exists.
"""
from __future__ import annotations

import threading

from rclpy.action import ActionClient as _RclpyActionClient


class ActionClient(_RclpyActionClient):
    """Drop-in replacement for ``rclpy.action.ActionClient`` (same arguments)."""

    def __init__(self, *args, **kwargs) -> None:
        self._request_lock = threading.RLock()
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
