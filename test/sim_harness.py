"""An in-process ur_sim node plus a client node on a private context, spun by a background executor."""
from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance, SpeedScalingFactor
from lifecycle_msgs.msg import State
from rcl_interfaces.msg import Log
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile
from ros_helpers import ros_context
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from ur_msgs.msg import Analog
from ur_msgs.srv import SetAnalogOutput, SetIO, SetPayload, SetSpeedSliderFraction

from ur_common.action_client import ActionClient
from ur_common.spin_thread import SpinThread
from ur_sim_driver.controllers.base import destroy_node
from ur_sim_driver.controllers.joint_trajectory import SPEED_SCALING_QOS
from ur_sim_driver.robot.io_bank import SPAN
from ur_sim_driver.robot.robot_state import PROTECTIVE_STOP, RUNNING
from ur_sim_driver.ros.main import make_executors
from ur_sim_driver.ros.node import UrSimNode

POSE_TOLERANCE = 1e-3  # [rad] a joint further than this from the remembered pose is moved back after a test
SETTLED_SPEED = 1e-3  # [rad/s] every joint slower than this: the arm is back at rest
TIMEOUT = 30.0  # [s] deadline of a wait: simulated time where the simulation steps, else wall time (a hang guard)


class Lockstep:
    """The simulation advances only inside the harness's waits, in the waiting thread, one control cycle at a time.

    The test decides when simulated time passes: a message handed to ur_sim while the test holds still arrives at
    the same simulated time however loaded the machine is, and every deadline is stated in simulated time. Waits
    for delivery alone (discovery, a goal's answer, a trajectory reaching its controller) hold the simulation
    still; waits for something the robot does step it and check the condition after every cycle.
    """

    # Control cycles a followed listener may lag: fewer than the history of 10 samples ur_sim's publishers keep (the
    # joint state broadcaster's depth, as upstream's). A sample the transport drops under load is then still in the
    # writer's history when the reader asks for it again; with 50 cycles of lag a loaded machine lost 92 joint states
    # of a followed listener for good (a clean-clone CI run).
    LAG_CYCLES = 5

    def __init__(self, node: UrSimNode) -> None:
        self.node = node
        self.LAG = self.LAG_CYCLES * node.sim.control_dt  # [s] of robot time
        self._lock = threading.Lock()  # one thread steps at a time
        self._views: list = []  # callables giving a followed listener's newest robot time [s]

    def follow(self, now) -> None:
        """Step only while `now()` (a listener's newest robot time [s]) is within LAG of the simulated time."""
        self._views.append(now)

    def unfollow(self, now) -> None:
        self._views.remove(now)

    def step(self, cycles: int = 1) -> None:
        with self._lock:
            for _ in range(cycles):
                self._wait_for_followers()
                self.node.step_once()

    def _wait_for_followers(self) -> None:
        """Hold still until every followed listener has caught up: stepping runs faster than a Python listener
        takes messages, and a loaded machine let 1000 queued messages overflow (the oldest are dropped)."""
        if not self._views:
            return
        t = _last_stamp(self.node)
        deadline = time.monotonic() + TIMEOUT
        while any(_lags(view(), t - self.LAG) for view in self._views):
            if time.monotonic() > deadline:
                raise TimeoutError(f'a followed listener stayed more than {self.LAG} s of robot time behind {t:.3f} s')
            time.sleep(0.0005)  # polling a condition that DDS delivery changes; no cycle passes meanwhile


def _last_stamp(node: UrSimNode) -> float:
    """The stamp [s] of the last cycle published, as a client reads it (followed views return such stamps)."""
    return node.clock.origin_ns * 1e-9 + node.sim.time - node.sim.control_dt


def _lags(seen: float | None, due: float) -> bool:
    """A followed listener's newest robot time `seen` [s] is before `due`; None (no message yet) never lags: its
    subscription may not have matched yet, and the cycles before it matched are not its to see."""
    return seen is not None and seen < due


class Pacer:
    """Steps a simulation in a thread of its own at the wall-clock pace of real time, for clients that wait on the
    wall clock (the example scripts, the script client), and holds it still while a message travels to ur_sim
    (`hold()`, and every `wait_still`) or while a followed client's view of robot time lags (`follow()`).

    A free-running simulation keeps moving while a loaded machine delays a message: under load, messages from a
    client to the trajectory gateway took up to 3.1 s (Fast DDS's writers send a heartbeat every 3 s by default,
    after which a reader asks again for a sample it lost), and a topic message of one example arrived after the
    next goal and preempted it. Paced, a message arrives at the simulated time it was sent at, however long it
    travels, and a client never falls so far behind that its joint-state queue overflows.
    """

    LAG = 0.01  # [s] of robot time a followed client may lag: 5 cycles, under its joint-state queue of 10

    def __init__(self, node: UrSimNode, speed: float = 1.0) -> None:
        """`speed`: robot seconds per wall second; 0 steps as fast as the followed clients take the robot's time
        (for a client whose every wait is on robot time, its wall-clock deadlines only guard against a hang)."""
        self.node = node
        self.speed = speed
        self._holds = 0
        self._lock = threading.Lock()
        self._views: list = []  # callables giving a client's newest robot time [s]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='pacer', daemon=True)

    def start(self) -> Pacer:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=TIMEOUT)

    def follow(self, now) -> None:
        """Step only while `now()` (a client's newest robot time [s]) is within LAG of the simulated time."""
        self._views.append(now)

    def unfollow(self, now) -> None:
        self._views.remove(now)

    @contextmanager
    def hold(self) -> Iterator[None]:
        """No cycle is stepped inside this block."""
        with self._lock:
            self._holds += 1
        try:
            yield
        finally:
            with self._lock:
                self._holds -= 1

    def _may_step(self) -> bool:
        if self._holds:
            return False
        t = _last_stamp(self.node)
        return all(view() >= t - self.LAG for view in self._views)

    def _run(self) -> None:
        dt = self.node.sim.control_dt
        next_wall = time.perf_counter()
        while not self._stop.is_set():
            if not self._may_step():
                time.sleep(0.0005)  # polling a condition that DDS delivery changes; no cycle is lost by it
                next_wall = time.perf_counter()  # robot time resumes at the wall clock's pace, without a burst
                continue
            self.node.step_once()
            if not self.speed:
                continue
            next_wall += dt / self.speed
            delay = next_wall - time.perf_counter()
            if delay > 0.0:
                time.sleep(delay)
            elif delay < -0.1:
                next_wall = time.perf_counter()  # a loaded machine: robot time runs slower, never in bursts


_lockstep: list[Lockstep] = []  # the running lockstep simulations, innermost last
_paced: list[Pacer] = []  # the running paced simulations, innermost last
_open: list[SimHarness] = []  # the harnesses of running simulations, oldest first


def open_harnesses() -> list[SimHarness]:
    """The harnesses of the simulations running now (a module fixture's, a test's own)."""
    return list(_open)


def wait_for(condition, timeout: float = TIMEOUT, what: str = 'condition') -> None:
    """Wait until `condition()` is true: stepping a lockstep simulation cycle by cycle (deadline `timeout` [s] of
    simulated time), or polling while a free-running one runs (deadline in wall time)."""
    if _lockstep:
        lockstep = _lockstep[-1]
        sim = lockstep.node.sim
        deadline = sim.time + timeout
        while not condition():
            if sim.time > deadline:
                raise TimeoutError(f'timed out after {timeout:.0f} s of simulated time waiting for {what}')
            lockstep.step()
        return
    _poll(condition, timeout, what)


def wait_answer(future, what: str = 'the answer', timeout: float = TIMEOUT):
    """Wait for a service's answer and return it. A lockstep simulation is held still, except for the cycles that a
    service waits for (a controller switch is applied in a cycle; the dashboard's power on and brake release wait for
    the robot mode): it takes effect at the same simulated time however long the request and answer travel. The
    deadline is wall time, a hang guard."""
    if not _lockstep:  # free or paced: the simulation runs on (a service may wait for cycles)
        _poll(future.done, timeout, what)
        return future.result()
    lockstep = _lockstep[-1]
    manager, host = lockstep.node.controller_manager, lockstep.node.host
    deadline = time.monotonic() + timeout
    while not future.done():
        if time.monotonic() > deadline:
            raise TimeoutError(f'timed out after {timeout:.0f} s waiting for {what}')
        if manager.pending or host.waiting:
            lockstep.step()
        else:
            time.sleep(0.0005)
    return future.result()


@contextmanager
def following(now) -> Iterator[None]:
    """Inside this block the innermost lockstep simulation steps only while `now()` (a listener's newest robot time
    [s], None before its first message) keeps within Lockstep.LAG of it: every message of every cycle reaches a
    listener that must see them all, however loaded the machine. Only around cycles in which its topic is
    published: a listener whose topic falls silent holds the simulation until the wait times out."""
    if not _lockstep:
        raise RuntimeError('following() needs a lockstep simulation (a paced one follows clients with Pacer.follow)')
    lockstep = _lockstep[-1]
    lockstep.follow(now)
    try:
        yield
    finally:
        lockstep.unfollow(now)


@contextmanager
def holding() -> Iterator[None]:
    """A paced simulation (the innermost) takes no step inside this block; a lockstep one steps only in waits."""
    with _paced[-1].hold() if _paced else contextlib.nullcontext():
        yield


def wait_still(condition, timeout: float = TIMEOUT, what: str = 'condition') -> None:
    """Wait until `condition()` is true holding the simulation still (lockstep or paced): for delivery (discovery, a
    goal's answer, a message reaching ur_sim). The deadline is wall time, a guard against a hang."""
    with holding():
        _poll(condition, timeout, what)


def _poll(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f'timed out after {timeout:.0f} s waiting for {what}')
        time.sleep(0.002)


def ready_action(action: ActionClient, probe_goals: bool = True) -> None:
    """Wait until `action`'s server answers this client on all three of its services, holding a lockstep
    simulation still.

    server_is_ready() says the client sees the server; the server may not yet see the client's response readers,
    and a response sent before that is lost (DDS discovery). With `probe_goals`, goals without points (rejected,
    no side effect: only for FollowJointTrajectory) are sent until one is answered; result and cancel requests
    about a goal the server never had prove the other two.
    """
    wait_still(action.server_is_ready, what=f'the action server {action._action_name}')
    deadline = time.monotonic() + TIMEOUT
    futures = []
    while probe_goals and not any(f.done() for f in futures):
        if time.monotonic() > deadline:
            raise TimeoutError(f'{action._action_name} answered none of {len(futures)} goals')
        futures.append(action.send_goal_async(FollowJointTrajectory.Goal()))
        resend = time.monotonic() + 2.0
        while not any(f.done() for f in futures) and time.monotonic() < resend:
            time.sleep(0.002)
    action.wait_until_answering(timeout=TIMEOUT)


def duration(t: float) -> Duration:
    ns = round(t * 1e9)
    return Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def point(q, t: float, qd=None, qdd=None) -> JointTrajectoryPoint:
    p = JointTrajectoryPoint(positions=[float(x) for x in q], time_from_start=duration(t))
    if qd is not None:
        p.velocities = [float(x) for x in qd]
    if qdd is not None:
        p.accelerations = [float(x) for x in qdd]
    return p


def trajectory(names, points) -> JointTrajectory:
    return JointTrajectory(joint_names=list(names), points=list(points))


@dataclass
class Recording:
    """Joint states received: their stamps as simulated time (K,) [s], positions and velocities (K, n)."""

    t: list = field(default_factory=list)
    q: list = field(default_factory=list)
    qd: list = field(default_factory=list)
    effort: list = field(default_factory=list)
    speed_scaling: list = field(default_factory=list)  # [%] from the speed scaling state broadcaster

    def arrays(self):
        return np.array(self.t), np.array(self.q), np.array(self.qd)


class SimHarness:
    """Client-side helpers against a running ur_sim."""

    def __init__(self, sim: UrSimNode, client: Node) -> None:
        self.sim = sim
        self.client = client
        p = sim.cfg.prefixed
        ctrl = sim.cfg.controller_name
        self.joints = list(sim.sim.joint_names)
        # Its own group: a busy subscription of the client node must never hold up goal responses.
        self.action = ActionClient(client, FollowJointTrajectory, p(f'{ctrl}/follow_joint_trajectory'),
                                   callback_group=ReentrantCallbackGroup())
        self.topic = _HandedOver(client.create_publisher(JointTrajectory, p(f'{ctrl}/joint_trajectory'), 10),
                                 lambda: sim.commands_received, 'the joint_trajectory message at ur_sim')
        self._scaling_inputs: dict[str, _HandedOver] = {}
        self.scaling = self.speed_scaling_input(ctrl)
        self.recording: Recording | None = None
        self.keeper: RobotKeeper | None = None  # set by running_sim: brings the robot back after each test
        self.pacer: Pacer | None = None  # set by running_sim for a paced simulation
        self._js_topic = p('joint_states')
        self._scaling_topic = p('speed_scaling_state_broadcaster/speed_scaling')
        self._recorder: Node | None = None
        self._recorder_followed: Lockstep | None = None  # the simulation that waits for the recorder
        self._listeners: list = []
        self._listener_count = 0
        self._rosout: list[tuple[str, str]] | None = None
        ready_action(self.action)
        wait_still(lambda: self.topic.get_subscription_count() > 0, what='the joint_trajectory subscriber')

    def speed_scaling_input(self, controller: str) -> _HandedOver:
        """A publisher on trajectory controller `controller`'s ~/speed_scaling_input, with upstream's QoS (transient
        local: a volatile publisher does not match it), whose publish() returns once the controller handled it."""
        if controller not in self._scaling_inputs:
            component = self.sim._trajectory[controller]
            publisher = self.client.create_publisher(SpeedScalingFactor,
                                                     self.sim.cfg.prefixed(f'{controller}/speed_scaling_input'),
                                                     SPEED_SCALING_QOS)
            wait_still(lambda: publisher.get_subscription_count() > 0, what=f'{controller}/speed_scaling_input')
            self._scaling_inputs[controller] = _HandedOver(publisher, lambda: component.speed_scaling_received,
                                                           'the speed_scaling_input message')
        return self._scaling_inputs[controller]

    def _on_js(self, msg: JointState) -> None:
        rec = self.recording
        if rec is not None:
            rec.t.append(self.sim.clock.sim_time(msg.header.stamp))
            rec.q.append(list(msg.position))
            rec.qd.append(list(msg.velocity))
            rec.effort.append(list(msg.effort))

    def _on_scaling(self, msg: Float64) -> None:
        rec = self.recording
        if rec is not None:
            rec.speed_scaling.append(msg.data)

    def record(self) -> Recording:
        """Start recording /joint_states (a subscription exists only while recording: in fast mode it is costly)."""
        self.recording = Recording()
        if self._recorder is None:
            # A node with its own executor and thread, so that it can be stopped cleanly before it is
            # destroyed (destroying entities under a spinning executor races in rclpy).
            node = Node('test_recorder', context=self.client.context)
            node.create_subscription(JointState, self._js_topic, self._on_js, QoSProfile(depth=1000))
            node.create_subscription(Float64, self._scaling_topic, self._on_scaling, QoSProfile(depth=1000))
            executor = SingleThreadedExecutor(context=self.client.context)
            executor.add_node(node)
            self._recorder = (node, SpinThread(executor, 'test_recorder').start())
            wait_for(lambda: self.recording.t, what='the first recorded joint state')
            self.recording = Recording()
            if _lockstep:  # the recording has every cycle: stepping waits for a recorder that lags
                self._recorder_followed = _lockstep[-1]
                self._recorder_followed.follow(self._recorded_until)
        return self.recording

    def _recorded_until(self) -> float | None:
        """The stamp [s] of the newest joint state recorded, None before the first."""
        rec = self.recording
        return self.sim.clock.origin_ns * 1e-9 + rec.t[-1] if rec is not None and rec.t else None

    def listen(self, msg_type, topic: str, callback, depth: int = 1000, latched: bool = False):
        """Subscribe `callback` on a node with its own executor and thread until the returned callable is called
        (at the latest when the harness closes).

        `latched`: transient local, so that what was published before the subscription matched arrives too.
        """
        self._listener_count += 1
        node = Node(f'test_listener_{self._listener_count}', context=self.client.context)
        durability = DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE
        node.create_subscription(msg_type, topic, callback, QoSProfile(depth=depth, durability=durability))
        executor = SingleThreadedExecutor(context=self.client.context)
        executor.add_node(node)
        entry = (node, SpinThread(executor, node.get_name()).start())
        self._listeners.append(entry)

        def stop() -> None:
            if entry in self._listeners:
                self._listeners.remove(entry)
                entry[1].stop()
                entry[0].destroy_node()
        return stop

    def rosout(self) -> list[tuple[str, str]]:
        """(logger name, text) of every /rosout line from the first call on; the list grows as lines arrive.

        /rosout keeps each line for late subscribers (transient local, 10 s): subscribed so, a line logged before
        this listener matched a process's writer still arrives, and the lines from before the call are told apart
        by their stamps (the system clock, as rcutils stamps them)."""
        if self._rosout is None:
            self._rosout = []
            since = time.time_ns()

            def keep(msg: Log) -> None:
                if msg.stamp.sec * 1_000_000_000 + msg.stamp.nanosec >= since:
                    self._rosout.append((msg.name, msg.msg))
            self.listen(Log, '/rosout', keep, latched=True)
        return self._rosout

    def close(self) -> None:
        """Stop recording and listening."""
        self.stop_recording(catch_up=False)
        for node, spinner in self._listeners:
            spinner.stop()
            node.destroy_node()
        self._listeners.clear()

    def stop_recording(self, catch_up: bool = True) -> Recording:
        """Stop recording and return what was recorded.

        With `catch_up`, every joint state of the cycles simulated before this call is in the recording: the
        recorder's own thread may lag the simulation (in fast mode, by many cycles), and what is still on its
        way is waited for. A goal's result can arrive before the joint states of its last cycles.
        """
        rec = self.recording
        if catch_up and rec is not None and self._recorder is not None:
            last_cycle = self.sim.sim.time - self.sim.sim.control_dt  # [s] stamp of the last finished cycle
            wait_still(lambda: bool(rec.t) and rec.t[-1] >= last_cycle - 1e-9,
                       what=f'the joint state stamped {last_cycle:.3f} s in the recording')
        rec, self.recording = self.recording, None  # the callback stops appending at once
        if self._recorder is not None:
            if self._recorder_followed is not None:
                self._recorder_followed.unfollow(self._recorded_until)
                self._recorder_followed = None
            node, spinner = self._recorder
            spinner.stop()
            node.destroy_node()
            self._recorder = None
        return rec

    @property
    def q(self) -> np.ndarray:
        return self.sim.sim.state().q

    def goal(self, points, names=None, path_tol=(), goal_tol=(), goal_time=0.0) -> FollowJointTrajectory.Goal:
        g = FollowJointTrajectory.Goal()
        g.trajectory = trajectory(names or self.joints, points)
        g.path_tolerance = [JointTolerance(name=n, position=p, velocity=v, acceleration=a) for n, p, v, a in path_tol]
        g.goal_tolerance = [JointTolerance(name=n, position=p, velocity=v, acceleration=a) for n, p, v, a in goal_tol]
        g.goal_time_tolerance = duration(goal_time)
        return g

    def send(self, goal, feedback=None, client=None):
        """Send a goal (to `client`, default the scaled trajectory controller's action) and wait for the server's
        answer, and for an accepted goal's arrival at its controller, with a lockstep simulation held still;
        returns the goal handle (check .accepted)."""
        return _send_held(self.sim, (client or self.action).send_goal_async, goal, feedback_callback=feedback).result()

    def cancel(self, handle):
        """Ask to cancel a goal of a trajectory controller and return the CancelGoal response, holding a lockstep
        simulation still: ur_sim applies a cancel as it arrives from the gateway and only then answers it, so the
        robot stops at the same simulated time however long the request and its answer travel."""
        future = handle.cancel_goal_async()
        wait_still(future.done, what='the cancel answer')
        return future.result()

    def result(self, handle, timeout: float = TIMEOUT):
        """Wait for the result of an accepted goal: (status, error_code, error_string). In lockstep the simulation
        steps until it has ended the goal and is then held still while the result is delivered, so that the test
        goes on from the same simulated time however long the delivery takes."""
        future = handle.get_result_async()
        if _lockstep:
            token = bytes(handle.goal_id.uuid)
            wait_for(lambda: token in self.sim.gateway.ended, timeout, 'the goal to end')
            wait_still(future.done, what='the goal result')
        else:
            wait_for(future.done, timeout, 'the goal result')
        r = future.result()
        return r.status, r.result.error_code, r.result.error_string

    def wait_sim_time(self, dt: float) -> None:
        """Wait until `dt` [s] of simulated time has passed."""
        t_end = self.sim.sim.time + dt
        wait_for(lambda: self.sim.sim.time >= t_end, what=f'{dt} s of simulated time')


class RobotKeeper:
    """Brings the robot back as a user would, over the driver's services: a protective stop unlocked through the
    dashboard once the robot allows it (5 s after the stop), power and brakes through the dashboard, the External
    Control program through resend_robot_program, the controllers that were active when this keeper was made, and
    through io_and_status_controller the outputs (digital, analog, tool voltage), the payload and the speed slider as
    they were then, and last the pose: a trajectory back on the scaled trajectory controller (activated for the move
    if another controller holds the joints, then the controllers are switched back).
    ``running_sim`` makes one for every simulation, and ``conftest.py`` recovers every running simulation after
    each test, so that a module's tests start from a working robot whatever the one before did."""

    def __init__(self, h: SimHarness) -> None:
        from cm_helpers import ControllerManagerClient
        self.h = h
        p = h.sim.cfg.prefixed
        group = ReentrantCallbackGroup()
        names = ('dashboard_client/unlock_protective_stop', 'dashboard_client/power_on',
                 'dashboard_client/power_off', 'dashboard_client/brake_release', 'dashboard_client/play',
                 'io_and_status_controller/resend_robot_program')
        self._trigger = {n.split('/')[-1]: h.client.create_client(Trigger, p(n), callback_group=group) for n in names}
        for client in self._trigger.values():
            wait_still(client.service_is_ready, what=f'the service {client.srv_name}')
        self._set_io = h.client.create_client(SetIO, p('io_and_status_controller/set_io'), callback_group=group)
        self._set_analog = h.client.create_client(SetAnalogOutput, p('io_and_status_controller/set_analog_output'),
                                                  callback_group=group)
        self._set_payload = h.client.create_client(SetPayload, p('io_and_status_controller/set_payload'),
                                                   callback_group=group)
        self._set_slider = h.client.create_client(SetSpeedSliderFraction,
                                                  p('io_and_status_controller/set_speed_slider'), callback_group=group)
        for client in (self._set_io, self._set_analog, self._set_payload, self._set_slider):
            wait_still(client.service_is_ready, what=f'the service {client.srv_name}')
        self.cm = ControllerManagerClient(h)
        self.remember()
        sim = h.sim
        self.io, self.payload, self.slider = sim.sim.io, sim.sim.payload, sim.scaling.slider

    def remember(self) -> None:
        """The controllers active now and the pose now are the ones to restore (for a fixture that switched
        controllers or moved the robot in its set-up)."""
        states = self.cm.states()
        self.loaded = list(states)
        self.active = {name for name, state in states.items() if state == 'active'}
        self.pose = self.h.q.copy()

    def call(self, name: str):
        """Call the Trigger service `name` (unlock_protective_stop, power_on, power_off, brake_release, play,
        resend_robot_program); its response."""
        return wait_answer(self._trigger[name].call_async(Trigger.Request()), f'the answer of {name}')

    def _call(self, name: str) -> str:
        answer = self.call(name)
        assert answer.success, f'{name}: {answer.message}'
        return answer.message

    def recover(self) -> None:
        robot = self.h.sim.robot
        # The hardware connected again, and the controllers loaded and configured as they were.
        for component in self.cm.components():
            if component.state.id != State.PRIMARY_STATE_ACTIVE:
                assert self.cm.set_component_state(component.name, State.PRIMARY_STATE_ACTIVE).ok, component.name
        states = self.cm.states()
        for name in self.loaded:
            if name not in states:
                assert self.cm.lifecycle('load', name), name
            if states.get(name, 'unconfigured') == 'unconfigured':
                assert self.cm.lifecycle('configure', name), name
        if robot.safety_mode == PROTECTIVE_STOP:
            wait_for(lambda: robot.unlock_wait() == 0.0, what='the 5 s before a protective stop may be unlocked')
            self._call('unlock_protective_stop')
        if robot.robot_mode != RUNNING:
            self._call('power_on')
            self._call('brake_release')
            wait_for(lambda: robot.robot_mode == RUNNING, what='the robot mode RUNNING')
        if not robot.program_running:  # headless: the driver sends its program; else it is played on the robot
            self._call('resend_robot_program' if self.h.sim.cfg.headless_mode else 'play')
        # The controller_stopper restores the controllers it stopped in the next cycle: wait for it, then compare.
        wait_for(lambda: self.h.sim._refusal is None, what='the robot ready to move and its controllers back')
        states = self.cm.states()
        now = {name for name, state in states.items() if state == 'active'}
        if now != self.active:
            answer = self.cm.switch(activate=sorted(self.active - now), deactivate=sorted(now - self.active))
            assert answer.ok, answer
        self._restore_io()
        self._restore_payload()
        if self.h.sim.scaling.slider != self.slider:
            self._answer(self._set_slider, SetSpeedSliderFraction.Request(speed_slider_fraction=self.slider))
        self._restore_pose()

    def _restore_pose(self) -> None:
        """Move back to the remembered pose at 1 rad/s of the joint that moves most (1 s at least; a third of a UR
        joint's speed limit, and a real-time module's tests wait for it in wall time)."""
        h = self.h
        distance = float(np.max(np.abs(h.q - self.pose)))
        if distance < POSE_TOLERANCE:
            return
        mover = h.sim.cfg.controller_name
        controllers = self.cm.controllers()
        joints = set(controllers[mover].required_command_interfaces)
        holding = sorted(name for name, c in controllers.items()
                         if c.state == 'active' and name != mover and joints & set(c.required_command_interfaces))
        if holding or controllers[mover].state != 'active':
            answer = self.cm.switch(activate=[mover], deactivate=holding)
            assert answer.ok, answer
        handle = h.send(h.goal([point(self.pose, max(1.0, distance / 1.0))]))
        assert handle.accepted, 'the trajectory back to the remembered pose was rejected'
        status, code, text = h.result(handle)
        assert code == 0, f'the trajectory back to the remembered pose failed ({status}, {code}: {text})'
        wait_for(lambda: float(np.max(np.abs(h.q - self.pose))) < POSE_TOLERANCE
                 and float(np.max(np.abs(h.sim.sim.state().qd))) < SETTLED_SPEED, 5.0, 'the arm settled back')
        if holding or mover not in self.active:
            answer = self.cm.switch(activate=holding, deactivate=[] if mover in self.active else [mover])
            assert answer.ok, answer

    def _answer(self, client, request) -> None:
        answer = wait_answer(client.call_async(request), f'the answer of {client.srv_name}')
        assert answer.success, f'{client.srv_name} refused {request}'

    def _restore_io(self) -> None:
        io, was = self.h.sim.sim.io, self.io
        for pin, (now, then) in enumerate(zip(io.digital_out, was.digital_out)):
            if now != then:
                self._answer(self._set_io, SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=pin,
                                                         state=float(then)))
        for pin in range(len(was.analog_out)):
            if (io.analog_out[pin], io.analog_out_domain[pin]) != (was.analog_out[pin], was.analog_out_domain[pin]):
                lo, hi = SPAN[was.analog_out_domain[pin]]
                data = Analog(pin=pin, domain=was.analog_out_domain[pin], state=(was.analog_out[pin] - lo) / (hi - lo))
                self._answer(self._set_analog, SetAnalogOutput.Request(data=data))
        if io.tool_voltage != was.tool_voltage:
            self._answer(self._set_io, SetIO.Request(fun=SetIO.Request.FUN_SET_TOOL_VOLTAGE,
                                                     state=float(was.tool_voltage)))

    def _restore_payload(self) -> None:
        now, then = self.h.sim.sim.payload, self.payload
        if now is then:
            return
        request = SetPayload.Request(mass=float(then.mass))
        request.center_of_gravity.x, request.center_of_gravity.y, request.center_of_gravity.z = map(float, then.cog)
        (request.ixx, request.iyy, request.izz, request.ixy, request.ixz,
         request.iyz) = map(float, then.inertia)
        self._answer(self._set_payload, request)
        wait_for(lambda: self.h.sim.sim.payload.mass == then.mass, what='the payload back')


class _HandedOver:
    """A publisher whose publish() returns once ur_sim has handled the message (`handled()`, a count, grew), holding
    a lockstep simulation still meanwhile; anything else is the publisher's."""

    def __init__(self, publisher, handled, what: str) -> None:
        self._publisher = publisher
        self._handled = handled
        self._what = what

    def publish(self, msg) -> None:
        with holding():  # from before the message leaves: a paced simulation must not step while it travels
            before = self._handled()
            self._publisher.publish(msg)
            wait_still(lambda: self._handled() > before, what=self._what)

    def __getattr__(self, name):
        return getattr(self._publisher, name)


def _send_held(sim: UrSimNode, send, goal, **kwargs):
    """`send(goal, **kwargs)` (an action client's send_goal_async) and wait for the answer, and for an accepted
    goal's arrival at its controller, with the simulation held still; returns the (done) future."""
    with holding():
        before = sim.commands_received
        future = send(goal, **kwargs)
        wait_still(future.done, what='the goal response')
        if future.result().accepted:
            wait_still(lambda: sim.commands_received > before, what='the goal at its controller')
    return future


def hand_over(harness: SimHarness, ur) -> None:
    """Make a URClient's trajectory publish and goal send (`ur`, ur_glue_planner's script client) return only once
    ur_sim has the message, the simulation held still meanwhile, as the harness's own do: with a paced simulation
    the scripts' stamps (robot time plus a margin) then hold however long a loaded machine takes to deliver.
    Reaches into the client's publisher and action client: the client offers no such hook, and users need none."""
    sim = harness.sim
    ur._topic = _HandedOver(ur._topic, lambda: sim.commands_received, 'the joint_trajectory message at ur_sim')
    send = ur._action.send_goal_async
    ur._action.send_goal_async = lambda goal, **kwargs: _send_held(sim, send, goal, **kwargs)


def _flatten(params: dict, prefix: str = '') -> dict:
    """Nested parameter mappings (as in a params file) as ROS names: {'dispenser': {'pin': 16}} -> dispenser.pin."""
    flat = {}
    for key, value in params.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, f'{prefix}{key}.'))
        else:
            flat[f'{prefix}{key}'] = value
    return flat


def _param(name, value) -> Parameter:
    return Parameter(name, value=value)


def yaml_params(path) -> dict:
    """The ros__parameters of a ur_sim parameter file, nested sections flattened to dotted names
    (``dispenser: {pin: 16}`` -> ``dispenser.pin``), as ``--params-file`` gives them to the node."""
    import yaml

    return _flatten(yaml.safe_load(Path(path).read_text())['/**']['ros__parameters'])


@contextmanager
def running_sim(lockstep: bool | None = None, paced: bool = False, ros_args: list[str] | None = None,
                pace_speed: float = 1.0, **params) -> Iterator[SimHarness]:
    """ur_sim with a client, on a private context.

    By default in lockstep (:class:`Lockstep`): the simulation advances only while the test waits for something
    the robot does. `paced`: stepped at real time's pace (`pace_speed` times it; 0: as fast as the followed clients
    take it) but held still during delivery (:class:`Pacer`), for clients that wait on the wall clock. With
    `real_time_factor` given (the wall clock is the subject) it runs free, paced to the wall clock; `lockstep=False`
    runs it free and as fast as possible.
    """
    if paced:
        lockstep = False
        params.setdefault('real_time_factor', 1.0)
    if lockstep is None:
        lockstep = 'real_time_factor' not in params
    params.setdefault('real_time_factor', 0.0)
    # As the driver's own tests launch it: the driver sends its program itself (resend_robot_program works).
    params.setdefault('headless_mode', True)
    # The dashboard's TCP port on a free port: tests run side by side (a test that needs 29999 asks for it).
    params.setdefault('dashboard_server', {'port': 0})
    params.setdefault('rtde', {'port': 0})
    params.setdefault('primary', {'port': 0})
    params.setdefault('secondary', {'port': 0})
    params.setdefault('realtime', {'port': 0})
    params.setdefault('interpreter', {'port': 0})
    with ros_context(ros_args) as ctx:
        sim = UrSimNode(context=ctx, parameter_overrides=[_param(k, v) for k, v in _flatten(params).items()],
                        start=not (lockstep or paced))
        client = Node('test_client', context=ctx)
        # ur_sim's nodes on the executors its executable gives them (main.make_executors: one of them walks some
        # 200 entities at every wake); the client on its own, woken only by its own answers and messages. One
        # thread, as a user's `rclpy.spin`: callbacks run in the order their messages arrived (on a thread pool two
        # feedback messages of one goal were appended out of order, a reentrant group lets them run side by side).
        executors = make_executors(sim)
        client_executor = SingleThreadedExecutor(context=ctx)
        client_executor.add_node(client)
        executors.append(client_executor)
        spinners = [SpinThread(e, f'test_executor_{i}').start() for i, e in enumerate(executors)]
        harness = None
        if lockstep:
            _lockstep.append(Lockstep(sim))
        pacer = Pacer(sim, pace_speed).start() if paced else None
        if pacer is not None:
            _paced.append(pacer)
        try:
            harness = SimHarness(sim, client)
            harness.pacer = pacer
            harness.keeper = RobotKeeper(harness)
            _open.append(harness)
            yield harness
        finally:
            # Every step runs even if one before it raises (a failed test can leave the harness half-closed): a node
            # left alive keeps its name in the next test's graph.
            with contextlib.ExitStack() as teardown:  # callbacks run last-registered first
                teardown.callback(rclpy.try_shutdown, context=ctx)
                teardown.callback(sim.destroy_node)
                teardown.callback(destroy_node, client)
                for spinner in spinners:
                    teardown.callback(spinner.stop)
                teardown.callback(sim.shutdown)
                if pacer is not None:
                    teardown.callback(pacer.stop)
                    teardown.callback(_paced.remove, pacer)
                if harness is not None:
                    teardown.callback(harness.close)
                    if harness in _open:
                        _open.remove(harness)
                if lockstep:
                    _lockstep.pop()


def driver_test_launch(tf_prefix: str = '', initial_joint_controller: str = 'scaled_joint_trajectory_controller',
                       **params):
    """ur_sim with the launch arguments the driver's own tests give ur_control.launch.py (test_common.py's driver
    test description): a UR5e, headless mode, the dashboard client, `initial_joint_controller` active, `tf_prefix`;
    the robot as URSim boots: powered off, its program stopped. `params` adds or overrides ur_sim parameters."""
    launch = dict(ur_type='ur5e', tf_prefix=tf_prefix, headless_mode=True, launch_dashboard_client=True,
                  initial_joint_controller=initial_joint_controller, activate_joint_controller=True,
                  start_powered_off=True)
    launch.update(params)
    return running_sim(**launch)


# The dashboard calls of the driver's own tests before each scenario (test_common.py's start_robot, then
# io_and_status_controller/resend_robot_program), in their order.
START_SEQUENCE = ('close_popup', 'close_safety_popup', 'stop', 'power_off', 'power_on', 'brake_release',
                  'unlock_protective_stop')


def start_robot(h: SimHarness, timeout: float = 10.0) -> None:
    """Start the robot as the driver's tests do before every scenario, over the services a user has: close the
    popups, stop the program, power off and on, release the brakes, unlock a protective stop (each answer checked),
    wait until the dashboard reports the robot mode RUNNING (`timeout` [s] of simulated time, upstream's wait), stop
    the program again and have the driver send its program (resend_robot_program, headless mode). Returns once the
    controller_stopper has brought back the controllers it stopped while the program did not run."""
    from ur_dashboard_msgs.msg import RobotMode
    from ur_dashboard_msgs.srv import GetRobotMode

    clients = getattr(h, '_start_clients', None)
    if clients is None:
        group = ReentrantCallbackGroup()
        clients = {name: h.client.create_client(Trigger, f'/dashboard_client/{name}', callback_group=group)
                   for name in START_SEQUENCE}
        clients['get_robot_mode'] = h.client.create_client(GetRobotMode, '/dashboard_client/get_robot_mode',
                                                           callback_group=group)
        clients['resend_robot_program'] = h.client.create_client(
            Trigger, h.sim.cfg.prefixed('io_and_status_controller/resend_robot_program'), callback_group=group)
        for client in clients.values():
            wait_still(client.service_is_ready, what=f'the service {client.srv_name}')
        h._start_clients = clients

    def call(name: str, request=None):
        answer = wait_answer(clients[name].call_async(request or Trigger.Request()), f'the answer of {name}')
        text = getattr(answer, 'message', '') or getattr(answer, 'answer', '')
        assert answer.success, f'{name} failed: {text}'
        return answer

    for name in START_SEQUENCE:
        call(name)
    wait_for(lambda: h.sim.robot.robot_mode == RUNNING, timeout, 'the robot mode RUNNING')
    assert call('get_robot_mode', GetRobotMode.Request()).robot_mode.mode == RobotMode.RUNNING
    call('stop')
    call('resend_robot_program')
    wait_for(lambda: h.sim.robot.program_running and h.sim._refusal is None, timeout,
             'the External Control program running and the controllers back')
