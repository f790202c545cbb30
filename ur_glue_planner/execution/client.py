"""A small client API over rclpy for scripts: the UR driver's interfaces without launch files or MATLAB.

In the spirit of MATLAB's ``universalrobot``: connect, read the joint state, send a trajectory on the topic,
send a goal through FollowJointTrajectory (blocking, or with a handle for feedback, cancel and wait), record
joint states, and solve IK. It works against ur_sim and against the real UR driver: it uses only their ROS
interfaces. Like node.py, this module is a ROS boundary; the rest of ur_glue_planner is pure.

Example:
    with URClient(namespace='/ur10', controller_name='vel_based_pos_traj_controller') as ur:
        q = ur.joint_state().q
        outcome = ur.send_joint_configuration(q + 0.1, end_time=2.0)
"""
from __future__ import annotations

import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Sequence

import numpy as np
import rclpy
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from rcl_interfaces.msg import Log
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import String

from ur_common.action_client import ActionClient
from ur_common.spin_thread import SpinThread
from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution import ros_conversions as conv
from ur_glue_planner.execution.joint_state_recording import JointStateRecorder, JointStateSample, Recording
from ur_glue_planner.execution.trajectory_goal import GoalOutcome, TrajectoryGoal, wait_until
from ur_glue_planner.motion.kinematics import IkResult, Kinematics

DEFAULT_CONTROLLER = 'scaled_joint_trajectory_controller'
IDLE_PACE = 0.002  # [s] rest of the client's spinning thread after a callback while nothing runs or records
DELIVERY_FACTOR = 4.0  # x the slowest goal answer seen so far: a loaded machine gets a margin in proportion


def delivery_margin(answers: Sequence[tuple[float, int]], delivery: float, points: int = 1) -> float:
    """Wall time [s] to allow for a goal of `points` points to reach the controller: `delivery`, or
    DELIVERY_FACTOR x the slowest of the earlier goals' `answers` (seconds, points), each scaled up to `points`,
    when that is longer. A loaded machine answers slowly, and a long goal takes longer to deliver and check."""
    worst = max((seconds * max(1.0, points / max(n, 1)) for seconds, n in answers), default=0.0)
    return max(delivery, DELIVERY_FACTOR * worst)


class URClient:
    """Connection to a UR driver (or ur_sim): joint states, the trajectory topic and the FollowJointTrajectory action.

    Args:
        namespace: prefix of every interface name, e.g. '/ur10'.
        controller_name: the trajectory controller, e.g. 'scaled_joint_trajectory_controller'.
        timeout: how long to wait for the action server and the first joint state [s].
        context: an initialised rclpy Context; a private one is created (and shut down by close()) when None.
    """

    def __init__(self, namespace: str = '', controller_name: str = DEFAULT_CONTROLLER, timeout: float = 10.0,
                 context: Context | None = None, node_name: str = 'ur_client') -> None:
        self._own_context = context is None
        if context is None:
            context = Context()
            rclpy.init(context=context)
        self.context = context
        ns = namespace.strip('/')
        prefix = f'/{ns}' if ns else ''
        self._prefix = prefix
        self.action_name = f'{prefix}/{controller_name}/follow_joint_trajectory'
        self.node = Node(node_name, context=context)
        self._latest: JointStateSample | None = None
        self._state_lock = threading.Lock()
        self._errors: list[tuple[float, str]] = []
        self._urdf: str | None = None
        self._recorders: list[JointStateRecorder] = []
        self._listeners: list[Callable[[JointStateSample], None]] = []
        #: (wall time [s] from sending to the answer, number of points) of each goal sent, oldest first.
        self.goal_answers: list[tuple[float, int]] = []
        self._history: deque[tuple[float, float]] = deque(maxlen=100)  # (wall, stamp) of recent joint states
        self.node.create_subscription(JointState, f'{prefix}/joint_states', self._on_joint_state, QoSProfile(depth=10))
        self.node.create_subscription(Log, '/rosout', self._on_log, QoSProfile(depth=50))
        # Subscribed for the client's lifetime: destroying entities under a spinning executor races in rclpy.
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(String, f'{prefix}/robot_description',
                                      lambda m: setattr(self, '_urdf', m.data), latched)
        self._topic = self.node.create_publisher(conv.JointTrajectory, f'{prefix}/{controller_name}/joint_trajectory',
                                                 10)
        self._action = ActionClient(self.node, FollowJointTrajectory, self.action_name)
        self._goals: weakref.WeakSet[TrajectoryGoal] = weakref.WeakSet()
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        self._spinner = SpinThread(self._executor, 'ur_client', pace=self._pace).start()
        try:
            wait_until(self._action.server_is_ready, timeout,
                       f'FollowJointTrajectory server {self.action_name} not found')
            try:
                self._action.wait_until_answering(timeout)
            except TimeoutError as e:
                raise ClientError(str(e)) from None
            wait_until(lambda: self._latest is not None, timeout, f'no joint states on {prefix}/joint_states')
            wait_until(lambda: self._topic.get_subscription_count() > 0, timeout,
                       f'no subscriber on {prefix}/{controller_name}/joint_trajectory')
        except ClientError:
            self.close()
            raise
        self.joint_names = self._latest.names

    def _pace(self) -> float:
        """Rest [s] of the spinning thread after each callback: none while a goal runs or a recording is on
        (every message counts then), IDLE_PACE otherwise (joint states stay fresh; the newest ones are kept)."""
        if self._recorders or any(not g.done for g in list(self._goals)):
            return 0.0
        return IDLE_PACE

    @property
    def prefix(self) -> str:
        """The namespace prefix of the driver's interfaces: '' or e.g. '/ur10'."""
        return self._prefix

    # ---- state -----------------------------------------------------------------------------------
    def _on_joint_state(self, msg: JointState) -> None:
        sample = JointStateSample(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, tuple(msg.name),
                                  np.array(msg.position), np.array(msg.velocity), np.array(msg.effort))
        with self._state_lock:
            self._latest = sample
            wall = time.monotonic()
            if not self._history or wall - self._history[-1][0] >= 0.01:  # ~1 s of history at any message rate
                self._history.append((wall, sample.t))
        for recorder in list(self._recorders):
            recorder.samples.append(sample)
        for listener in list(self._listeners):
            listener(sample)

    def _on_log(self, msg: Log) -> None:
        if msg.level >= Log.ERROR:
            self._errors.append((time.monotonic(), msg.msg))
            del self._errors[:-20]

    def joint_state(self) -> JointStateSample:
        """The newest joint state received."""
        with self._state_lock:
            return self._latest

    def on_joint_state(self, listener: Callable[[JointStateSample], None]) -> Callable[[], None]:
        """Call `listener` with every joint state from now on, in the spinning thread (one subscription serves every
        reader on the node); returns the function that stops it."""
        self._listeners.append(listener)
        return lambda: self._listeners.remove(listener)

    def start_recording(self, rate: float = 50.0, t0: float | None = None) -> JointStateRecorder:
        """Record joint states from now on, resampled at `rate` [Hz] of message time (seed 2: 50 Hz).

        Args:
            rate: sampling rate [Hz].
            t0: robot time [s] of sample 0 (e.g. a trajectory's start stamp); default: the first message.
        """
        recorder = JointStateRecorder(rate, t0)
        self._recorders.append(recorder)
        return recorder

    def record(self, duration: float, rate: float = 50.0, timeout: float | None = None) -> Recording:
        """Record for `duration` [s] of message (robot) time, sampled at `rate` [Hz]; blocks until done."""
        recorder = self.start_recording(rate)
        wait_until(lambda: recorder.span() >= duration - 1.0 / rate, timeout or duration * 10 + 10.0,
                   'recording did not finish')
        return self.stop_recording(recorder, duration)

    def stop_recording(self, recorder: JointStateRecorder, duration: float | None = None,
                       raw: bool = False) -> Recording:
        """Stop `recorder` and return its samples at its rate (the first `duration` [s] when given), or every
        message received (`raw`)."""
        self._recorders.remove(recorder)
        return recorder.raw() if raw else recorder.resample(duration)

    def sleep(self, duration: float, timeout: float | None = None) -> None:
        """Wait `duration` [s] of robot time (joint state stamps), which runs at any real-time factor."""
        t_end = self.joint_state().t + duration
        wait_until(lambda: self.joint_state().t >= t_end, timeout or duration * 10 + 10.0, 'robot time did not advance')

    # ---- kinematics ------------------------------------------------------------------------------
    def robot_description(self, timeout: float = 10.0) -> str:
        """The URDF on robot_description (transient local, as the UR driver and ur_sim publish it)."""
        wait_until(lambda: self._urdf is not None, timeout, f'no URDF on {self._prefix}/robot_description')
        return self._urdf

    def kinematics(self, frame: str = 'tool0', base_pose: np.ndarray | None = None) -> Kinematics:
        """Pinocchio kinematics of `frame` from the robot's own URDF; base_pose (4, 4) places base_link in a world."""
        return Kinematics(self.robot_description(), self.joint_names, frame, base_pose=base_pose)

    def ik(self, target: np.ndarray, q0: Sequence[float] | None = None, frame: str = 'tool0',
           weights: Sequence[float] | None = None, base_pose: np.ndarray | None = None) -> IkResult:
        """Joint positions putting `frame` at `target` (4, 4) [m]; q0 defaults to the current joint state."""
        kin = self.kinematics(frame, base_pose)
        q_start = self.joint_state().q if q0 is None else np.asarray(q0, dtype=float)
        return kin.ik(np.asarray(target, dtype=float), q_start, None if weights is None else np.asarray(weights))

    # ---- commands --------------------------------------------------------------------------------
    def publish_trajectory(self, times: Sequence[float], q: np.ndarray, qd: np.ndarray | None = None,
                           qdd: np.ndarray | None = None, start_time: float = 0.0) -> None:
        """Send a JointTrajectory on the topic (fire and forget).

        Args:
            times: (N,) time_from_start [s].
            q, qd, qdd: (N, n) [rad, rad/s, rad/s^2]; qd and qdd may be None.
            start_time: header.stamp in robot time [s] (see `now()`); 0 starts on arrival.
        """
        self._topic.publish(conv.joint_trajectory(self.joint_names, times, q, qd, qdd, start_time))

    def now(self) -> float:
        """Robot time [s]: the newest joint state's stamp (simulated time on ur_sim)."""
        return self.joint_state().t

    def time_rate(self) -> float:
        """How fast robot time runs against the wall clock (1 on a real robot; higher on a fast simulation)."""
        with self._state_lock:
            history = list(self._history)
        if len(history) < 2 or history[-1][0] - history[0][0] < 0.05:
            return 1.0
        (w0, t0), (w1, t1) = history[0], history[-1]
        return max(1.0, (t1 - t0) / (w1 - w0))

    def start_time(self, lead: float = 0.1, delivery: float = 0.3, points: int = 1) -> float:
        """A trajectory start stamp safely in the future [s of robot time]: `lead` [s] of robot time plus the
        `delivery_margin` [s of wall time] for a goal of `points` points to arrive, scaled by `time_rate()`."""
        margin = delivery_margin(self.goal_answers, delivery, points)
        return self.now() + lead + margin * self.time_rate()

    def send_joint_configuration(self, q: Sequence[float], end_time: float, wait: bool = True,
                                 **kwargs) -> GoalOutcome | TrajectoryGoal:
        """Move to configuration q (n,) [rad], arriving at rest after end_time [s], through the action."""
        q = np.asarray(q, dtype=float)[None, :]
        return self.follow_trajectory(q, np.zeros_like(q), None, [end_time], wait=wait, **kwargs)

    def follow_trajectory(self, q: np.ndarray, qd: np.ndarray | None, qdd: np.ndarray | None,
                          times: Sequence[float], path_tolerance: Sequence[JointTolerance] | None = None,
                          goal_tolerance: Sequence[JointTolerance] | None = None, goal_time_tolerance: float = 0.0,
                          wait: bool = True, feedback_callback: Callable | None = None,
                          timeout: float = 10.0, start_time: float = 0.0) -> GoalOutcome | TrajectoryGoal:
        """Send a trajectory through FollowJointTrajectory.

        Args:
            q, qd, qdd: (N, n) positions [rad], velocities [rad/s] (or None), accelerations [rad/s^2] (or None).
            times: (N,) time_from_start [s].
            path_tolerance, goal_tolerance: control_msgs/JointTolerance lists (see `tolerances()`).
            goal_time_tolerance: [s].
            wait: block until the result (returns GoalOutcome), else return a TrajectoryGoal at once.
            feedback_callback: called with each FollowJointTrajectory.Feedback.
            timeout: for the goal response [s].
            start_time: header.stamp in robot time [s] (see `now()`); 0 starts on arrival.

        Raises:
            ClientError: the goal was rejected (with the server's logged reason when it gave one) or not answered.
        """
        goal = self.trajectory_goal(q, qd, qdd, times, path_tolerance, goal_tolerance, goal_time_tolerance)
        return self.send_goal(goal, start_time, wait, feedback_callback, timeout)

    def trajectory_goal(self, q: np.ndarray, qd: np.ndarray | None, qdd: np.ndarray | None,
                        times: Sequence[float], path_tolerance: Sequence[JointTolerance] | None = None,
                        goal_tolerance: Sequence[JointTolerance] | None = None,
                        goal_time_tolerance: float = 0.0) -> FollowJointTrajectory.Goal:
        """The FollowJointTrajectory goal of `follow_trajectory` (same arguments), built but not sent; its start
        stamp is set by `send_goal`."""
        goal = FollowJointTrajectory.Goal()
        goal.trajectory = conv.joint_trajectory(self.joint_names, times, np.atleast_2d(q), qd, qdd)
        goal.path_tolerance = list(path_tolerance or [])
        goal.goal_tolerance = list(goal_tolerance or [])
        goal.goal_time_tolerance = conv.duration(goal_time_tolerance)
        return goal

    def send_goal(self, goal: FollowJointTrajectory.Goal, start_time: float = 0.0, wait: bool = True,
                  feedback_callback: Callable | None = None,
                  timeout: float = 10.0) -> GoalOutcome | TrajectoryGoal:
        """Stamp a built goal with `start_time` [s of robot time] (0 starts on arrival) and send it; see
        `follow_trajectory`. Building a long goal takes time, so a start stamped only now keeps its margin."""
        goal.trajectory.header.stamp = conv.stamp(start_time)
        holder: list[TrajectoryGoal] = []
        sent_at = time.monotonic()
        future = self._action.send_goal_async(
            goal, feedback_callback=lambda msg: holder and holder[0]._feedback(msg))
        wait_until(future.done, timeout, f'no answer to the goal from {self.action_name}')
        self.goal_answers.append((time.monotonic() - sent_at, len(goal.trajectory.points)))
        handle = future.result()
        if not handle.accepted:
            raise ClientError(f'goal rejected by {self.action_name}: {self._rejection_reason(sent_at)}')
        holder.append(TrajectoryGoal(handle, feedback_callback))
        self._goals.add(holder[0])
        return holder[0].wait() if wait else holder[0]

    def _rejection_reason(self, since: float) -> str:
        # rclpy's goal response carries no reason; the server logs it (ur_sim and the UR driver both do).
        deadline = time.monotonic() + 0.5
        while time.monotonic() < deadline:
            reasons = [m for t, m in self._errors if t >= since - 0.05]
            if reasons:
                return reasons[-1]
            time.sleep(0.01)
        return 'the server gave no reason on /rosout'

    def tolerances(self, position: Sequence[float] | float, velocity: Sequence[float] | float = 0.0,
                   acceleration: Sequence[float] | float = 0.0) -> list[JointTolerance]:
        """JointTolerance per joint (>0 sets, 0 keeps the controller default, -1 disables the check)."""
        n = len(self.joint_names)
        pos, vel, acc = (np.broadcast_to(np.asarray(x, dtype=float), (n,)) for x in (position, velocity, acceleration))
        return [JointTolerance(name=name, position=float(p), velocity=float(v), acceleration=float(a))
                for name, p, v, a in zip(self.joint_names, pos, vel, acc)]

    # ---- lifetime --------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop spinning and release the node (and the private context)."""
        self._spinner.stop()
        # rclpy's destroy_node leaves action clients alive, and each would keep the node in the graph.
        self._action.destroy()
        self.node.destroy_node()
        if self._own_context:
            rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> URClient:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
