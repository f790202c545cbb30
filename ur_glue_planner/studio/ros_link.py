"""The studio's ROS side: the live robot (/joint_states, /robot_description) and running a plan on it.

Running reuses :func:`ur_glue_planner.execution.run.execute`, the planner node's own execution (one
FollowJointTrajectory goal per segment with the job's tolerances, progress from the feedback, a message for every
result code; a stop request cancels the active goal).
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import JointState, PointCloud2
from std_msgs.msg import String

from ur_common.spin_thread import SpinThread
from ur_glue_planner.errors import ClientError, PlanningError
from ur_glue_planner.execution.bead_listener import BeadListener, BeadPoints
from ur_glue_planner.execution.part_measure import SCAN_TOPIC
from ur_glue_planner.execution.run import Interrupted, describe, execute
from ur_glue_planner.job import GlueJob
from ur_glue_planner.motion.plan import GluePlan, plan_job
from ur_glue_planner.studio.part_view import measured_part
from ur_glue_planner.studio.run_client import StudioClient
from ur_sim_driver.description.part_scan import from_cloud

READ_PERIOD = 1.0 / 60.0  # [s] rest of the ROS thread after each callback: the page shows at most 60 poses a second
REST_READ_PERIOD = 0.1  # [s] the same while the robot rests: a move is seen within it
MOVED = 1e-6  # [rad] a joint further than this from a pose seen before has moved (less is invisible on the page)


@dataclass(frozen=True)
class LiveState:
    """Newest joint state of the live robot: stamp [s], names, positions [rad], and the wall time it arrived."""

    stamp: float
    names: tuple[str, ...]
    q: np.ndarray
    received: float


@dataclass(frozen=True)
class RunResult:
    """How a run ended: succeeded, the error code (None if it never reached the robot), the message shown, and
    whether it ended because the plan from the robot's state failed (``message`` is then the planner's)."""

    succeeded: bool
    error_code: int | None
    message: str
    planning_failed: bool = False


class LiveRobot:
    """Subscriptions to a robot's joint states and robot description, spun in a background thread.

    Args:
        namespace: Prefix of the topics, e.g. '' or '/ur10'.
        context: An initialised rclpy context (a private one is made and shut down by close() if None).
    """

    def __init__(self, namespace: str = '', context: Context | None = None) -> None:
        self._own_context = context is None
        if context is None:
            context = Context()
            rclpy.init(context=context)
        self.context = context
        ns = namespace.strip('/')
        self.prefix = f'/{ns}' if ns else ''
        self.node = Node('ur_glue_studio', context=context)
        self._lock = threading.Lock()
        self._state: LiveState | None = None
        self._urdf: str | None = None
        self.node.create_subscription(JointState, f'{self.prefix}/joint_states', self._on_joint_state,
                                      QoSProfile(depth=10))
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(String, f'{self.prefix}/robot_description', self._on_description, latched)
        # The simulated bead (ur_sim with the dispenser only; a real driver has no such topic).
        self.bead_listener = BeadListener(self.node, self.prefix)
        # The cell's part scanners (ur_sim in a scene with scanners; a cell without them has no such topic).
        self._scan: np.ndarray | None = None
        self.node.create_subscription(PointCloud2, f'{self.prefix}/{SCAN_TOPIC}', self._on_scan, latched)
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        # Joint states come every control cycle (500 Hz) and the page shows at most 60 poses a second, none while
        # the robot rests: the thread rests after each callback (the subscription keeps the newest; the bead and
        # scan messages are whole).
        self._moving = True
        self._spinner = SpinThread(self._executor, 'studio_ros',
                                   pace=lambda: READ_PERIOD if self._moving else REST_READ_PERIOD).start()
        self._run_thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.client: StudioClient | None = None  # the runs' connection, made by the first run

    def _on_joint_state(self, msg: JointState) -> None:
        state = LiveState(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, tuple(msg.name),
                          np.array(msg.position), time.monotonic())
        with self._lock:
            last, self._state = self._state, state
        self._moving = (last is None or last.names != state.names
                        or float(np.max(np.abs(state.q - last.q), initial=0.0)) > MOVED)

    def _on_scan(self, msg: PointCloud2) -> None:
        profiles = from_cloud(msg)
        with self._lock:
            self._scan = profiles

    def scan(self) -> np.ndarray | None:
        """The newest part scan (scanners, beams, 3) [m] in base_link, or None (no scanners)."""
        with self._lock:
            return self._scan

    def _on_description(self, msg: String) -> None:
        with self._lock:
            self._urdf = msg.data

    def state(self) -> LiveState | None:
        """The newest joint state, or None before the first."""
        with self._lock:
            return self._state

    def urdf(self) -> str | None:
        """The robot's URDF, or None before it arrived."""
        with self._lock:
            return self._urdf

    def bead(self) -> tuple[int, BeadPoints | None]:
        """(how many bead messages arrived, the newest bead in the planner's world frame or None)."""
        return self.bead_listener.received, self.bead_listener.bead()

    # ---- running a plan --------------------------------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self._run_thread is not None and self._run_thread.is_alive()

    def start_run(self, job: GlueJob, namespace: str, controller_name: str, log: Callable[[str], None],
                  on_progress: Callable[[str, float, float], None], on_done: Callable[[RunResult, GluePlan | None],
                                                                                    None],
                  timeout: float = 10.0) -> None:
        """Plan ``job`` from the robot's current state and execute it in a background thread.

        ``on_done`` receives the result and the plan executed (None if planning or connecting failed). Every run
        uses the same client (:mod:`~ur_glue_planner.studio.run_client`), made by the first.
        """
        if self.running:
            raise RuntimeError('a run is already in progress')
        self._stop.clear()

        def work() -> None:
            plan = None
            try:
                ur = self._client_for(namespace, controller_name, timeout)
            except ClientError as exc:
                on_done(RunResult(False, None, f'cannot connect: {exc}'), None)
                return
            ur.runs += 1
            try:
                found, reason = measured_part(self.scan(), job, log)
                if reason is not None:
                    on_done(RunResult(False, None, f'part refused, nothing dispensed: {reason}'), None)
                    return
                try:
                    plan = plan_job(job, ur.joint_state().q, part=found)
                except PlanningError as exc:
                    on_done(RunResult(False, None, str(exc), planning_failed=True), None)
                    return
                log(f'planned from the current state: total {plan.summary.total_duration:.2f} s')
                # The glue gun is switched as by the planner node, where the driver has set_io; the simulated
                # bead is cleared first where ur_sim has one.
                gun = ur.gun if ur.gun.available(timeout=2.0) else None
                bead = ur.bead if gun is not None and ur.bead.available(timeout=1.0) else None
                outcome, _ = execute(ur, plan, self._stop, log=log, on_progress=on_progress, gun=gun, bead=bead)
                text = describe(outcome)
                on_done(RunResult(outcome.succeeded, outcome.error_code, text), plan)
            except Interrupted as exc:
                on_done(RunResult(False, None, f'stopped: the {exc} goal was cancelled, the robot holds'), plan)
            except (PlanningError, ClientError) as exc:
                on_done(RunResult(False, None, str(exc)), plan)

        self._run_thread = threading.Thread(target=work, daemon=True, name='ur_glue_studio_run')
        self._run_thread.start()

    def _client_for(self, namespace: str, controller_name: str, timeout: float) -> StudioClient:
        """The client of every run on this controller: made by the first run (or anew for another controller)."""
        if self.client is not None and self.client.key != (namespace, controller_name):
            self.client.close()
            self.client = None
        if self.client is None:
            self.client = StudioClient(namespace, controller_name, timeout, self.context)
        return self.client

    def request_stop(self) -> None:
        """Ask the run to cancel its active goal, at once and without waiting (the run's loop looks every 20 ms)."""
        self._stop.set()

    def stop_run(self, timeout: float = 15.0) -> None:
        """Cancel the active goal (the robot stops and holds) and wait for the run to end."""
        self._stop.set()
        if self._run_thread is not None:
            self._run_thread.join(timeout)

    def close(self) -> None:
        """Stop a run, stop spinning, release the node (and the private context)."""
        if self.running:
            self.stop_run()
        if self.client is not None:
            self.client.close()
            self.client = None
        self._spinner.stop()
        self.node.destroy_node()
        if self._own_context:
            rclpy.try_shutdown(context=self.context)
