"""One trajectory controller's ROS interfaces, in the gateway process (``gateway_process.py``; ``gateway_link.py``
says why).

For each trajectory controller (scaled_joint_trajectory_controller, joint_trajectory_controller,
passthrough_trajectory_controller) a ``TrajectoryGateway`` on the process's node serves
``<controller>/follow_joint_trajectory`` and subscribes to ``<controller>/joint_trajectory``. It asks the
simulation whether the controller may take what arrives (:class:`~ur_sim_driver.gateway.gateway_link.Admit`: the
simulation owns which controller is active and whether the robot can move, and answers with upstream's words),
validates it, and hands each accepted trajectory to the simulation, which executes it and reports back.

Order: goal requests, their acceptance and topic messages are handled one at a time in one mutually
exclusive callback group, and each accepted trajectory is handed over at acceptance, in that order. So the
newest accepted goal is the one that runs, and the ones it replaces end as upstream's do: aborted,
INVALID_GOAL "Current goal preempted by new incoming action.".
"""
from __future__ import annotations

import threading
import time
import traceback
from dataclasses import replace

from control_msgs.action import FollowJointTrajectory
from rclpy.action import CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from trajectory_msgs.msg import JointTrajectory

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway.gateway_link import (
    Cancel,
    Canceled,
    Dropped,
    Ended,
    Feedback,
    GatewayConfig,
    Received,
    Start,
)
from ur_sim_driver.gateway.goal_intake import ArrayGoalActionServer
from ur_sim_driver.gateway.memory import release_memory, trim_heap
from ur_sim_driver.gateway.sim_pipe import SimPipe
from ur_sim_driver.gateway.trajectory_cdr import read_joint_trajectory
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion import passthrough, result_codes
from ur_sim_driver.motion.command_arrays import CommandArrays, from_points
from ur_sim_driver.motion.start_stamp import far_start
from ur_sim_driver.motion.tolerances import resolve_tolerances
from ur_sim_driver.motion.validation import validate_trajectory

# From this many points on, the memory of a received trajectory is handed back to the system when it is done.
LARGE_TRAJECTORY = 10_000
RECEIVED_TIMEOUT = 10.0  # [s] of wall time for the simulation to confirm an accepted goal (a hang guard)
NOT_ANSWERING = 'ur_sim does not answer (shutting down?)'
_SHUTDOWN = Ended(None, result_codes.INVALID_GOAL, 'ur_sim is shutting down.')


class _Waiter:
    """One goal's end, handed from the receiving thread to the goal's execute callback."""

    def __init__(self, points: int) -> None:
        self.points = points  # the trajectory's length
        self.event = threading.Event()
        self.ended: Ended | None = None
        self.canceled: bool | None = None


class TrajectoryGateway:
    """One controller's action server and topic subscription on `node`, talking to the simulation."""

    def __init__(self, node: Node, cfg: GatewayConfig, name: str, pipe: SimPipe) -> None:
        self.node = node
        self.log = node.get_logger().get_child(name)
        self.cfg = cfg
        self.name = name
        self._pipe = pipe
        self._lock = threading.Lock()
        self._waiters: dict[bytes, _Waiter] = {}
        self._handles: dict[bytes, object] = {}
        self._received: dict[bytes, threading.Event] = {}  # set when the simulation's controller has the goal
        self._pending: dict[int, CommandArrays] = {}  # converted goals between goal callback and acceptance
        self.passthrough = name in cfg.passthrough
        ns = cfg.namespace.strip('/')
        base = f'/{ns}/{name}' if ns else f'/{name}'
        ordered = MutuallyExclusiveCallbackGroup()
        # Goal requests arrive without their points, which come as arrays (goal_intake.py).
        self._action = ArrayGoalActionServer(
            node, f'{base}/follow_joint_trajectory', execute_callback=self._execute,
            goal_callback=self._on_goal, handle_accepted_callback=self._on_accepted,
            cancel_callback=lambda _: CancelResponse.ACCEPT, callback_group=ordered)
        if not self.passthrough:  # upstream's passthrough controller has no topic interface
            node.create_subscription(JointTrajectory, f'{base}/joint_trajectory', self._on_topic, 10,
                                     callback_group=ordered, raw=True)

    # ---- validation --------------------------------------------------------------------------------
    def _validate(self, cmd: CommandArrays, what: str, now: float) -> str | None:
        """Why `cmd` is refused by the driver's rules, or None; `now` [s]: the simulated time. Checked on the
        stamps' clock, so that a message quotes the client's own stamp."""
        cfg = self.cfg
        strict = cfg.strict_limits
        now += cfg.clock.origin_ns * 1e-9
        # The passthrough controller needs every joint and does not look at the end velocity.
        reason = validate_trajectory(
            cmd, joint_names_config=cfg.joints, now=now, q_min=cfg.q_min if strict else None,
            q_max=cfg.q_max if strict else None, v_max=cfg.v_max if strict else None,
            allow_partial=cfg.allow_partial and not self.passthrough,
            allow_nonzero_end_velocity=cfg.allow_nonzero_end_velocity or self.passthrough)
        if reason is None:
            note = far_start(cmd.header_stamp, now, time.time())
            # Two call sites: rclpy's logger raises ValueError when one call site changes its severity.
            if note is not None and note.wall_clock:
                self.log.warning(f'{what} {note.text}')
            elif note is not None:
                self.log.info(f'{what} {note.text}')
        return reason

    def _on_sim_time(self, cmd: CommandArrays) -> CommandArrays:
        """`cmd` with its start stamp as the simulation counts time (the stamps' origin taken off)."""
        if not self.cfg.clock.origin_ns:
            return cmd
        return replace(cmd, header_stamp=self.cfg.clock.sim_seconds(cmd.header_stamp))

    def _on_goal(self, goal: FollowJointTrajectory.Goal) -> GoalResponse:
        try:
            return self._answer_goal(goal)
        except Exception:  # noqa: BLE001 - rclpy drops an exception here silently: the client would wait forever
            self.log.error(f'Rejected FollowJointTrajectory goal: ur_sim failed to check it:\n{traceback.format_exc()}')
            return GoalResponse.REJECT

    def _answer_goal(self, goal: FollowJointTrajectory.Goal) -> GoalResponse:
        cmd = self._action.arrays_of(goal)
        if cmd is None:  # converted by rclpy: the points are in the message
            traj = goal.trajectory
            cmd = from_points(traj.joint_names, conv.time_to_sec(traj.header.stamp), traj.points)
        # Upstream's JTC rejects goals while inactive, and the controller_stopper deactivates it while the robot
        # cannot move: the simulation, which owns both, says whether this one may take the goal.
        admission = self._pipe.admit(self.name, topic=False)
        if admission is None:
            reason = NOT_ANSWERING
        elif admission.reason is not None:
            reason = admission.reason
        elif self.passthrough and self.busy():
            reason = passthrough.BUSY
        else:
            reason = self._validate(cmd, 'FollowJointTrajectory goal', admission.now)
        if reason is None and self.passthrough:
            reason = passthrough.check_goal(cmd, self.cfg.joints, [t.name for t in goal.goal_tolerance])
        if reason is None and goal.multi_dof_trajectory.points:
            reason = 'multi_dof_trajectory is not supported by this controller (it has no multi-DOF joints)'
        if reason is not None:
            self.log.error(f'Rejected FollowJointTrajectory goal: {reason}')
            return GoalResponse.REJECT
        self._pending[id(goal)] = self._on_sim_time(cmd)
        return GoalResponse.ACCEPT

    def busy(self) -> bool:
        """A goal is being converted, accepted or executed (its execute callback has not ended)."""
        with self._lock:
            return bool(self._waiters) or bool(self._pending)

    def _on_accepted(self, goal_handle) -> None:
        goal = goal_handle.request
        cmd = self._pending.pop(id(goal))
        if self.passthrough:
            tolerances = passthrough.tolerances_of(conv.tolerance_specs(goal.goal_tolerance), self.cfg.joints,
                                                   conv.duration_to_sec(goal.goal_time_tolerance))
        else:
            tolerances, reason = resolve_tolerances(
                self.cfg.defaults, self.cfg.joints, conv.tolerance_specs(goal.path_tolerance),
                conv.tolerance_specs(goal.goal_tolerance), conv.duration_to_sec(goal.goal_time_tolerance))
            if reason is not None:
                self.log.error(f'Goal tolerances ignored, using the defaults: {reason}')
        large = cmd.count >= LARGE_TRAJECTORY
        self._start(goal_handle, cmd, tolerances)
        if large:
            # Handed over: the taken C request's many small blocks and the arrays were freed in executor
            # threads' heaps, which keep the pages until trimmed.
            del cmd
            trim_heap()

    def _start(self, goal_handle, cmd, tolerances) -> None:
        token = bytes(goal_handle.goal_id.uuid)
        received = threading.Event()
        with self._lock:
            self._waiters[token] = _Waiter(cmd.count)
            self._handles[token] = goal_handle
            self._received[token] = received
        self._send(Start(token, cmd, tolerances, self.name))
        # Reported executing once the simulation's controller has it: a client that holds a paced simulation until
        # then knows that the goal cannot come after its start (acceptance alone did not tell it: docs/parts.md).
        if not received.wait(RECEIVED_TIMEOUT):
            self.log.warning(f'the simulation did not confirm the goal within {RECEIVED_TIMEOUT:.0f} s; reporting it '
                             'executing anyway')
        with self._lock:
            self._received.pop(token, None)
        goal_handle.execute()

    def _on_topic(self, data: bytes) -> None:
        try:
            cmd = read_joint_trajectory(data)
        except TrajectoryError as exc:
            self.log.error(f'Dropped JointTrajectory message: {exc}')
            self._send(Dropped(self.name))
            return
        admission = self._pipe.admit(self.name, topic=True)
        reason = NOT_ANSWERING if admission is None else admission.reason
        if reason is not None:
            self.log.warning(f'Dropped JointTrajectory message: {reason}')
            self._send(Dropped(self.name))
            return
        reason = self._validate(cmd, 'JointTrajectory message', admission.now)
        if reason is not None:
            self.log.error(f'Dropped JointTrajectory message: {reason}')
            self._send(Dropped(self.name))
            return
        cmd = self._on_sim_time(cmd)
        self._send(Start(None, cmd, None, self.name))
        if cmd.count >= LARGE_TRAJECTORY:
            del cmd
            trim_heap()  # the arrays may have been carved from an executor thread's heap: give its pages back

    # ---- execution -----------------------------------------------------------------------------------
    def _execute(self, goal_handle) -> FollowJointTrajectory.Result:
        token = bytes(goal_handle.goal_id.uuid)
        with self._lock:
            waiter = self._waiters[token]
        cancel_sent = False
        while not waiter.event.wait(0.005):
            if goal_handle.is_cancel_requested and not cancel_sent:
                self._send(Cancel(token, self.name))
                cancel_sent = True
        with self._lock:
            self._waiters.pop(token, None)
            self._handles.pop(token, None)
        large = waiter.points >= LARGE_TRAJECTORY
        if large:
            # Once more a little later: rclpy lets go of the message's last references after this returns.
            release_memory()
            threading.Timer(1.0, release_memory).start()
        if waiter.canceled:
            goal_handle.canceled()
            self.log.info('Goal canceled; holding the measured position')
            # An empty result, as upstream's controllers give a canceled goal (goal_cancelled_callback).
            return FollowJointTrajectory.Result()
        ended = waiter.ended
        result = FollowJointTrajectory.Result(error_code=ended.code, error_string=ended.message)
        if ended.code == result_codes.SUCCESSFUL and not ended.aborted:
            goal_handle.succeed()
        else:
            self.log.warning(f'Goal aborted ({result_codes.NAMES[ended.code]}): {ended.message}')
            goal_handle.abort()
        return result

    def _send(self, message: object) -> None:
        self._pipe.send(message)

    def owns(self, token: bytes) -> bool:
        with self._lock:
            return token in self._waiters

    def end_all(self) -> int:
        """The simulation is gone: every goal ends. Returns how many goals were still executing."""
        with self._lock:
            waiters = list(self._waiters.values())
            received = list(self._received.values())
        for event in received:
            event.set()
        for waiter in waiters:
            if not waiter.event.is_set():
                waiter.ended = _SHUTDOWN
                waiter.event.set()
        return len(waiters)

    def dispatch(self, message: object) -> None:
        """A Received, Ended, Canceled or Feedback for one of this controller's goals."""
        if isinstance(message, Received):
            with self._lock:
                received = self._received.get(message.token)
            if received is not None:
                received.set()
            return
        with self._lock:
            waiter = self._waiters.get(message.token)
            handle = self._handles.get(message.token)
        if waiter is None:
            return
        if isinstance(message, Ended):
            waiter.ended = message
            waiter.event.set()
        elif isinstance(message, Canceled):
            if message.ok:
                waiter.canceled = True
                waiter.event.set()
        elif isinstance(message, Feedback) and handle is not None:
            fb = FollowJointTrajectory.Feedback()
            fb.header.stamp = self.cfg.clock.stamp(message.t)
            fb.joint_names = list(self.cfg.joints)
            fb.desired = conv.trajectory_point(*message.desired)
            fb.desired.time_from_start = conv.sec_to_duration(message.desired_time)
            fb.actual = conv.trajectory_point(*message.actual)
            fb.actual.time_from_start = conv.sec_to_duration(message.actual_time)
            fb.error = conv.trajectory_point(*message.error)
            try:
                handle.publish_feedback(fb)
            except Exception:  # the goal may have ended in an executor thread meanwhile
                pass


