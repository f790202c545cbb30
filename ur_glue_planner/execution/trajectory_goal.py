"""A FollowJointTrajectory goal the client sent and the server accepted: its feedback, cancel, and how it ended.

The client's executor spins in another thread; the waits here are on the wall clock (`wait_until`), as a script's
are against a real robot.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from action_msgs.msg import GoalStatus
from control_msgs.action import FollowJointTrajectory

from ur_glue_planner.errors import ClientError

STATUS_NAMES = {GoalStatus.STATUS_SUCCEEDED: 'succeeded', GoalStatus.STATUS_ABORTED: 'aborted',
                GoalStatus.STATUS_CANCELED: 'canceled'}


def wait_until(condition: Callable[[], bool], timeout: float, what: str) -> None:
    """Return once `condition()` holds; ClientError naming `what` after `timeout` [s] of wall time."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise ClientError(f'{what} within {timeout:.1f} s')
        time.sleep(0.001)


@dataclass(frozen=True)
class GoalOutcome:
    """How a FollowJointTrajectory goal ended: the control_msgs error code and string, and the goal status."""

    error_code: int
    error_string: str
    status: str

    @property
    def succeeded(self) -> bool:
        return self.status == 'succeeded' and self.error_code == FollowJointTrajectory.Result.SUCCESSFUL


class TrajectoryGoal:
    """An accepted goal: latest feedback, cancel() and wait()."""

    def __init__(self, handle, on_feedback: Callable | None) -> None:
        self._handle = handle
        self._result_future = handle.get_result_async()
        self.feedback = None
        self._on_feedback = on_feedback

    def _feedback(self, msg) -> None:
        self.feedback = msg.feedback
        if self._on_feedback is not None:
            self._on_feedback(msg.feedback)

    @property
    def done(self) -> bool:
        return self._result_future.done()

    def cancel(self, timeout: float = 5.0, meanwhile: Callable[[], object] | None = None) -> None:
        """Ask the server to cancel; the robot stops and holds (the result then says canceled). `meanwhile` runs
        once the request is on its way, before its answer [s of wall time, `timeout`] is waited for."""
        future = self._handle.cancel_goal_async()
        if meanwhile is not None:
            meanwhile()
        wait_until(future.done, timeout, 'no answer to the cancel request')

    @property
    def executing(self) -> bool:
        """The server reported the goal executing (or already ended): it has handed it to its controller."""
        return self._handle.status != GoalStatus.STATUS_ACCEPTED and self._handle.status != GoalStatus.STATUS_UNKNOWN

    def wait(self, timeout: float | None = None) -> GoalOutcome:
        """Block until the goal ends (timeout [s] of wall time, None = no limit) and return its outcome."""
        wait_until(self._result_future.done, float('inf') if timeout is None else timeout, 'the goal did not end')
        r = self._result_future.result()
        return GoalOutcome(r.result.error_code, r.result.error_string, STATUS_NAMES.get(r.status, str(r.status)))
