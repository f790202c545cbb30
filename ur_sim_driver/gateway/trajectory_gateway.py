"""The trajectory controllers' ROS interfaces, in a process of their own (see ``gateway_link.py`` for why).

This process holds one node, ``ur_sim_trajectory_gateway`` (the controllers' own nodes, named after them as in
ros2_control, are ur_sim's). For each trajectory controller (scaled_joint_trajectory_controller,
joint_trajectory_controller, passthrough_trajectory_controller) it serves ``<controller>/follow_joint_trajectory``
and subscribes to ``<controller>/joint_trajectory``; it asks the simulation whether the controller may take what
arrives (:class:`~ur_sim_driver.gateway.gateway_link.Admit`: the simulation owns which controller is active and
whether the robot can move, and answers with upstream's words), validates it, and hands each accepted trajectory
to the simulation, which executes it and reports back.

Order: goal requests, their acceptance and topic messages are handled one at a time in one mutually
exclusive callback group, and each accepted trajectory is handed over at acceptance, in that order. So the
newest accepted goal is the one that runs, and the ones it replaces end as upstream's do: aborted,
INVALID_GOAL "Current goal preempted by new incoming action.".
"""
from __future__ import annotations

import faulthandler
import itertools
import signal
import sys
import threading
import time
import traceback
from dataclasses import replace
from multiprocessing.connection import Connection

import rclpy
from control_msgs.action import FollowJointTrajectory
from rclpy.action import CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from trajectory_msgs.msg import JointTrajectory

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway.dds_profile import free_received_samples
from ur_sim_driver.gateway.gateway_link import (
    STOP,
    Admission,
    Admit,
    Cancel,
    Canceled,
    Dropped,
    Ended,
    Feedback,
    GatewayConfig,
    Received,
    Start,
)
from ur_sim_driver.gateway.goal_intake import ArrayGoalActionServer, intake_error
from ur_sim_driver.gateway.memory import release_memory, trim_heap, use_mmap_for_large_blocks
from ur_sim_driver.gateway.trajectory_cdr import read_joint_trajectory
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion import passthrough, result_codes
from ur_sim_driver.motion.command_arrays import CommandArrays, from_points
from ur_sim_driver.motion.start_stamp import far_start
from ur_sim_driver.motion.tolerances import resolve_tolerances
from ur_sim_driver.motion.validation import validate_trajectory

# From this many points on, the memory of a received trajectory is handed back to the system when it is done.
LARGE_TRAJECTORY = 10_000
# How long a goal or message waits for the simulation's Admission [s of wall time]: the simulation answers from
# its receiving thread at once, so only a simulation that is gone or hung takes this long.
ADMIT_TIMEOUT = 10.0
RECEIVED_TIMEOUT = 10.0  # [s] of wall time for the simulation to confirm an accepted goal (a hang guard)
NOT_ANSWERING = 'ur_sim does not answer (shutting down?)'
NODE_NAME = 'ur_sim_trajectory_gateway'
_SHUTDOWN = Ended(None, result_codes.INVALID_GOAL, 'ur_sim is shutting down.')


class _Waiter:
    """One goal's end, handed from the receiving thread to the goal's execute callback."""

    def __init__(self, points: int) -> None:
        self.points = points  # the trajectory's length
        self.event = threading.Event()
        self.ended: Ended | None = None
        self.canceled: bool | None = None


class _Shared:
    """What the controllers of this process share: the pipe (one sender at a time) and the questions to the
    simulation that wait for its answer."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.send_lock = threading.Lock()
        self._numbers = itertools.count()
        self._lock = threading.Lock()
        self._asked: dict[int, list] = {}  # request -> [event, Admission | None]

    def admit(self, controller: str, topic: bool) -> Admission | None:
        """Ask the simulation whether `controller` may take a goal (or a topic message) now; None if it does not
        answer within ADMIT_TIMEOUT."""
        request = next(self._numbers)
        slot = [threading.Event(), None]
        with self._lock:
            self._asked[request] = slot
        _send(self, Admit(request, controller, topic))
        slot[0].wait(ADMIT_TIMEOUT)
        with self._lock:
            self._asked.pop(request, None)
        return slot[1]

    def answered(self, admission: Admission) -> None:
        with self._lock:
            slot = self._asked.get(admission.request)
        if slot is not None:
            slot[1] = admission
            slot[0].set()

    def end_all(self) -> None:
        """The simulation is gone: every question ends unanswered."""
        with self._lock:
            slots = list(self._asked.values())
        for slot in slots:
            slot[0].set()


class TrajectoryGateway:
    """One controller's action server and topic subscription on `node`, talking to the simulation."""

    def __init__(self, node: Node, cfg: GatewayConfig, name: str, shared: _Shared) -> None:
        self.node = node
        self.log = node.get_logger().get_child(name)
        self.cfg = cfg
        self.name = name
        self._shared = shared
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
        admission = self._shared.admit(self.name, topic=False)
        if admission is None:
            reason = NOT_ANSWERING
        elif admission.reason is not None:
            reason = admission.reason
        elif self.passthrough and self._busy():
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

    def _busy(self) -> bool:
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
        admission = self._shared.admit(self.name, topic=True)
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
        _send(self._shared, message)

    def owns(self, token: bytes) -> bool:
        with self._lock:
            return token in self._waiters

    def end_all(self) -> None:
        """The simulation is gone: every goal ends."""
        with self._lock:
            waiters = list(self._waiters.values())
            received = list(self._received.values())
        for event in received:
            event.set()
        for waiter in waiters:
            if not waiter.event.is_set():
                waiter.ended = _SHUTDOWN
                waiter.event.set()

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


def _send(shared: _Shared, message: object) -> None:
    with shared.send_lock:
        try:
            shared.conn.send(message)
        except (OSError, BrokenPipeError):
            pass  # the simulation is gone; the receiving thread ends every goal


def _receive(shared: _Shared, gateways: dict[str, TrajectoryGateway], stopped: threading.Event) -> None:
    """Hand the simulation's messages to the controllers until it says stop or the pipe closes."""
    try:
        while True:
            message = shared.conn.recv()
            if message == STOP:
                break
            if isinstance(message, Admission):
                shared.answered(message)
            else:
                for gateway in gateways.values():
                    if gateway.owns(message.token):
                        gateway.dispatch(message)
                        break
    except (OSError, EOFError):
        pass
    shared.end_all()
    for gateway in gateways.values():
        gateway.end_all()
    stopped.set()


def run_gateway(conn: Connection) -> None:
    """Serve the controllers' interfaces until the simulation says stop (or its end of the pipe closes)."""
    # The parent stops this process through the pipe; Ctrl-C in a terminal reaches both, and the parent must
    # be the one to decide (it ends the goals first).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    faulthandler.register(signal.SIGUSR1)  # `kill -USR1 <pid>` prints every thread's stack, for a hang
    use_mmap_for_large_blocks()
    cfg: GatewayConfig = conn.recv()
    profile = free_received_samples()  # a large goal's receive buffer is not kept after it
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    shared = _Shared(conn)
    executor = MultiThreadedExecutor(num_threads=4)
    try:
        node = Node(NODE_NAME, namespace=cfg.namespace or '/')
    finally:
        if profile is not None:
            profile.unlink(missing_ok=True)  # read when the node was made
    gateways = {name: TrajectoryGateway(node, cfg, name, shared) for name in cfg.controllers}
    executor.add_node(node)
    if intake_error() is not None:
        node.get_logger().warning(
            f'goal requests are converted point by point (slow for long trajectories): {intake_error()}')
    stopped = threading.Event()
    threading.Thread(target=_receive, args=(shared, gateways, stopped), name='gateway_receive', daemon=True).start()
    try:
        while not stopped.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
        # Let the execute callbacks return their (shutdown) results before the context goes.
        for _ in range(20):
            executor.spin_once(timeout_sec=0.01)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown(timeout_sec=2.0)
        node.destroy_node()
        rclpy.try_shutdown()
        conn.close()


def main() -> None:
    """``python -m ur_sim_driver.gateway.trajectory_gateway PIPE_FD``, as GatewayLink starts it."""
    run_gateway(Connection(int(sys.argv[1])))


if __name__ == '__main__':
    main()
