"""``/trajectory_until_node``: the driver's trajectory_until_node, a client of ur_sim's own controllers.

``~/execute`` (ur_msgs/action/FollowJointTrajectoryUntil) runs a trajectory on the motion controller (parameter
``motion_controller``, by default the initial joint controller, as the driver's launch file sets it) and ends it
early when the until condition triggers (``until_type`` TOOL_CONTACT: tool_contact_controller's
``detect_tool_contact``). As upstream (``trajectory_until_node.cpp``), over the ROS graph like any client:

* a goal is refused while one runs, for an unknown until type, and when either action server does not answer or
  does not accept its part (the until goal first, then the trajectory);
* feedback is the trajectory controller's, passed on;
* the trajectory's successful end reports its error code and string with ``until_condition_result``
  NOT_TRIGGERED; a triggered condition succeeds with TRIGGERED and "Trajectory finished successfully by triggering
  until condition."; the other goal is then cancelled. Upstream takes whichever result arrives first; a trajectory
  aborted by the robot's tool-contact stop ends in the same cycle as the condition, so ur_sim waits for the until
  goal's outcome when the trajectory did not succeed (aborted: " Trajectory action was aborted. Aborting goal."
  appended to its string, unless the condition triggered);
* cancel is accepted and cancels both.

Upstream waits 1 s of wall time for each acceptance; ur_sim waits :data:`ACCEPT_TIMEOUT`, so that a loaded machine
slows a goal's acceptance without refusing it.
"""
from __future__ import annotations

import threading

from action_msgs.msg import GoalStatus
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from ur_msgs.action import FollowJointTrajectoryUntil, ToolContact

from ur_common.action_client import ActionClient  # rclpy's loses a fast goal response
from ur_sim_driver.controllers import startup
from ur_sim_driver.controllers.base import Component, Host

Until = FollowJointTrajectoryUntil
ACCEPT_TIMEOUT = 10.0  # [s] of wall time for each action server to answer a goal
_TRIGGERED = 'Trajectory finished successfully by triggering until condition.'


class _Run:
    """One goal in progress: the two client goals and the result, once one of them ended."""

    def __init__(self) -> None:
        self.trajectory = None  # client goal handles
        self.until = None
        self.result: Until.Result | None = None
        self.status = GoalStatus.STATUS_UNKNOWN
        self.trajectory_outcome: tuple[int, Until.Result] | None = None  # ended without success, until pending
        self.done = threading.Event()
        self.lock = threading.Lock()

    def finish(self, status: int, result: Until.Result) -> bool:
        """Record the first outcome; False if one was recorded already."""
        with self.lock:
            if self.done.is_set():
                return False
            self.status, self.result = status, result
            self.done.set()
            return True


class TrajectoryUntilNode(Component):
    """The FollowJointTrajectoryUntil action server (one goal at a time)."""

    name = 'trajectory_until_node'
    type_name = 'ur_robot_driver/trajectory_until_node'  # a node of the driver, not a controller
    is_controller = False

    def on_configure(self, host: Host, node: Node) -> None:
        cfg = host.cfg
        default = startup.initial_joint_controller(cfg) or cfg.controller_name
        motion = node.declare_parameter('motion_controller', default).value
        self._trajectory_action = cfg.prefixed(f'{motion}/follow_joint_trajectory')
        self._until_action = cfg.prefixed('tool_contact_controller/detect_tool_contact')
        self._trajectory_client: ActionClient | None = None  # made by the first goal (_make_clients)
        self._until_client: ActionClient | None = None
        self._run: _Run | None = None
        self._busy = threading.Lock()
        ActionServer(node, Until, '~/execute', execute_callback=self._execute, goal_callback=self._on_goal,
                     cancel_callback=self._on_cancel, callback_group=MutuallyExclusiveCallbackGroup())

    def _make_clients(self) -> None:
        """The clients of the two actions, made when the first goal comes. An action client receives every status
        array and feedback message of its action: made at start, it had ur_sim's process turn each status array of
        a thousand-goal storm into Python objects (up to 0.7 s each, holding the interpreter lock the simulation
        loop needs every cycle), for a node that may never run a goal (issue 42)."""
        if self._trajectory_client is not None:
            return
        # One callback at a time: feedback passed on in the order it came (on the MultiThreadedExecutor a reentrant
        # group runs two feedback callbacks side by side, and they may publish out of order). None of them blocks.
        clients = MutuallyExclusiveCallbackGroup()
        self._until_client = ActionClient(self.node, ToolContact, self._until_action, callback_group=clients)
        self._trajectory_client = ActionClient(self.node, FollowJointTrajectory, self._trajectory_action,
                                               callback_group=clients)

    # ---- goal, cancel (server callbacks) ----------------------------------------------------------------------------
    def _on_goal(self, goal: Until.Goal) -> GoalResponse:
        logger = self.node.get_logger()
        if self._run is not None:
            logger.error('Node is currently busy, rejecting action goal.')
            return GoalResponse.REJECT
        if goal.until_type != Until.Goal.TOOL_CONTACT:
            logger.error(f'Received unknown until-type {goal.until_type}; valid: TOOL_CONTACT (0). Until type not '
                         'defined, double check the types in the action definition.')
            return GoalResponse.REJECT
        self._make_clients()
        for client, what in ((self._trajectory_client, 'Trajectory'), (self._until_client, 'Until')):
            if not client.wait_for_server(timeout_sec=ACCEPT_TIMEOUT):
                logger.error(f'{what} action server not available.')
                return GoalResponse.REJECT
        run = _Run()
        run.until = self._send(self._until_client, ToolContact.Goal(), None)
        if run.until is None:
            logger.error('Until condition was rejected by server.')
            return GoalResponse.REJECT
        trajectory = FollowJointTrajectory.Goal(
            trajectory=goal.trajectory, path_tolerance=goal.path_tolerance, goal_tolerance=goal.goal_tolerance,
            goal_time_tolerance=goal.goal_time_tolerance)
        run.trajectory = self._send(self._trajectory_client, trajectory, self._on_feedback)
        if run.trajectory is None:
            logger.error('Trajectory rejected by server.')
            run.until.cancel_goal_async()
            return GoalResponse.REJECT
        self._run = run
        run.trajectory.get_result_async().add_done_callback(lambda f: self._trajectory_ended(run, f.result()))
        run.until.get_result_async().add_done_callback(lambda f: self._until_ended(run, f.result()))
        return GoalResponse.ACCEPT

    def _send(self, client: ActionClient, goal, feedback):
        """Send a goal and wait for its answer: the accepted goal's handle, or None."""
        answered = threading.Event()
        future = client.send_goal_async(goal, feedback_callback=feedback)
        future.add_done_callback(lambda _: answered.set())
        if not answered.wait(ACCEPT_TIMEOUT):
            future.cancel()
            return None
        handle = future.result()
        return handle if handle.accepted else None

    def _on_cancel(self, goal_handle) -> CancelResponse:
        self.node.get_logger().info('Cancel received. Cancelling trajectory-until action.')
        run = self._run
        if run is not None:
            run.until.cancel_goal_async()
            run.trajectory.cancel_goal_async()
        return CancelResponse.ACCEPT

    # ---- the two client goals ---------------------------------------------------------------------------------------
    def _on_feedback(self, message) -> None:
        handle = self._handle
        if handle is not None:
            f = message.feedback
            handle.publish_feedback(Until.Feedback(header=f.header, joint_names=f.joint_names, desired=f.desired,
                                                   actual=f.actual, error=f.error))

    def _trajectory_ended(self, run: _Run, wrapped) -> None:
        result = Until.Result(error_code=wrapped.result.error_code, error_string=wrapped.result.error_string,
                              until_condition_result=Until.Result.NOT_TRIGGERED)
        if wrapped.status == GoalStatus.STATUS_SUCCEEDED:
            if run.finish(wrapped.status, result):
                run.until.cancel_goal_async()
            return
        if wrapped.status == GoalStatus.STATUS_ABORTED:
            result.error_string += ' Trajectory action was aborted. Aborting goal.'
        else:
            result.error_string += ' Trajectory action was canceled.'
        # The robot's tool-contact stop aborts the trajectory in the cycle the condition triggers, and the two
        # results may arrive in either order: the until goal's outcome decides (it ends at the latest when its
        # cancel arrives).
        with run.lock:
            run.trajectory_outcome = (wrapped.status, result)
        run.until.cancel_goal_async()

    def _until_ended(self, run: _Run, wrapped) -> None:
        result = Until.Result(until_condition_result=Until.Result.NOT_TRIGGERED)
        if wrapped.status == GoalStatus.STATUS_SUCCEEDED:
            result.error_code, result.until_condition_result = Until.Result.SUCCESSFUL, Until.Result.TRIGGERED
            result.error_string = _TRIGGERED
            status = wrapped.status
        else:
            with run.lock:
                ended = run.trajectory_outcome
            if ended is not None:  # the trajectory ended first, and not because the condition triggered
                status, result = ended
            else:
                status = wrapped.status
                result.error_string = ('Until action was canceled.' if status == GoalStatus.STATUS_CANCELED else
                                       'Until action was aborted. Aborting goal.')
        if run.finish(status, result):
            run.trajectory.cancel_goal_async()

    # ---- execution ---------------------------------------------------------------------------------------------------
    _handle = None

    def _execute(self, goal_handle) -> Until.Result:
        run = self._run
        self._handle = goal_handle
        try:
            while not run.done.wait(0.05):
                if not self.host.context.ok():
                    goal_handle.abort()
                    return Until.Result(error_string='ur_sim is shutting down')
            result, logger = run.result, self.node.get_logger()
            if run.status == GoalStatus.STATUS_SUCCEEDED:
                logger.info('Trajectory finished by triggering until condition.'
                            if result.until_condition_result == Until.Result.TRIGGERED else
                            'Trajectory finished successfully, did not trigger until condition.')
                goal_handle.succeed()
            elif run.status == GoalStatus.STATUS_CANCELED and goal_handle.is_cancel_requested:
                goal_handle.canceled()
            else:
                logger.error(result.error_string)
                goal_handle.abort()
            return result
        finally:
            self._handle = None
            self._run = None
