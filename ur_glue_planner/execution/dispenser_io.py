"""The glue gun on the robot's digital output: switched through the UR driver's ``io_and_status_controller``.

``/io_and_status_controller/set_io`` (ur_msgs/SetIO, FUN_SET_DIGITAL_OUT) is the same call on ur_sim and on a
real UR driver, so against a real robot this switches the real gun. Switch times follow the controller's
scaled clock (see switch_timer.py): the stamps of its ``controller_state`` messages, and the factor it advances
by. The scaled controller advances by the robot's speed scaling, which only the
``speed_scaling_state_broadcaster`` reports: its ``controller_state.speed_scaling_factor`` is the base class's
own factor (upstream's publish_state), 1.0 unless a ``speed_scaling_input`` came. The plain controller advances
by that own factor, which its ``controller_state`` does report. Every call is logged with the robot time it was
made at. :meth:`off` switches the gun off and waits for the answer: the executor calls it
at the end, on failure and on cancel.
"""
from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from builtin_interfaces.msg import Time
from control_msgs.msg import JointTrajectoryControllerState
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

from ur_glue_planner.execution.service_call import call_idempotent
from ur_glue_planner.execution.switch_timer import ScaledClock, SwitchEvent, SwitchSequence

SET_IO = '/io_and_status_controller/set_io'
IO_STATES = '/io_and_status_controller/io_states'
PLAIN_CONTROLLER = 'joint_trajectory_controller'  # advances by its own factor; the others by the robot's
# [s] of robot time a paced ur_sim may run past the newest state this client handled, away from a switch: the
# client keeps up (its queues of 20 do not overflow for long) while the simulation runs as fast as both can.
FREE_AHEAD = 0.1
# The client's last word counts, also for a ur_sim that subscribes after it was said: latched.
PACE_QOS = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)



@dataclass(frozen=True)
class OutputChange:
    """The output as the robot reported it on io_states: its new state, seen at robot time [s] (the newest
    controller_state stamp then, within a cycle or two) and at trajectory time [s] (None outside a bead)."""

    pin: int
    state: bool
    robot_time: float
    trajectory_time: float | None


@dataclass(frozen=True)
class SwitchRecord:
    """A set_io call made: the event, the robot time [s] and the trajectory time [s] it was made at."""

    event: SwitchEvent
    robot_time: float
    trajectory_time: float
    success: bool | None


class DispenserIO:
    """Switches one digital output on a trajectory's clock.

    Args:
        node: The client's node (its executor spins elsewhere).
        controller_state: Topic of the trajectory controller's state (stamps; speed_scaling_factor without
            `robot_scaling`).
        robot_scaling: Topic of the robot's speed scaling in percent (std_msgs/Float64) that the controller advances
            by, or None: the controller_state's own factor.
        pace_topic: Keep a ur_sim started with this pace_topic in step with the client, or None. Paced, the gun
            needs the robot's time while no goal is armed: :meth:`follow_joint_states` feeds :meth:`robot_time`
            every joint state's stamp from the client's own subscription (one subscription serves both).
    The controller's period is taken from the stamps of consecutive state messages: an event is due half a
    period early, so that the call lands in the cycle nearest to its time (within half a period: 1 ms at
    500 Hz, 4 ms at 125 Hz, plus the service's delivery).
    """

    def __init__(self, node: Node, controller_state: str, robot_scaling: str | None = None,
                 pace_topic: str | None = None) -> None:
        self.node = node
        self._robot_factor: float | None = None  # [0, 1] the latest robot speed scaling, when that is the clock's
        self.client = node.create_client(SetIO, SET_IO)
        self._lock = threading.Lock()
        self._clock: ScaledClock | None = None
        self._sequence: SwitchSequence | None = None
        self._last_stamp: float | None = None
        self.records: list[SwitchRecord] = []
        self.changes: list[OutputChange] = []
        self._watched: dict[int, bool] = {}
        self._pending: list[tuple[SwitchEvent, float, float, object]] = []
        node.create_subscription(JointTrajectoryControllerState, controller_state, self._on_state,
                                 QoSProfile(depth=20))
        node.create_subscription(IOStates, IO_STATES, self._on_io, QoSProfile(depth=20))
        # ur_sim in step with this client (its pace_topic): the newest robot time handled, held at the time of a
        # switch call until its answer arrives, so the simulation waits for the call instead of running past it.
        self._pace = node.create_publisher(Clock, pace_topic, PACE_QOS) if pace_topic else None
        self._last_joint_state: float | None = None
        self._pace_sent: float | None = None  # the last hold time published
        self._holds: list[float] = []  # robot times [s] a paced ur_sim must not pass (hold())
        self._uses_robot_scaling = robot_scaling is not None
        if robot_scaling is not None:
            node.create_subscription(Float64, robot_scaling, self._on_robot_scaling, QoSProfile(depth=20))

    def available(self, timeout: float = 2.0) -> bool:
        """Whether the set_io service answers (the io_and_status_controller is running)."""
        return self.client.wait_for_service(timeout_sec=timeout)

    @property
    def paced(self) -> bool:
        """A ur_sim runs in step with this client (pace_topic)."""
        return self._pace is not None

    def arm(self, events: list[SwitchEvent], start: float) -> None:
        """Switch ``events`` on the clock of a goal that starts at robot time ``start`` [s]."""
        with self._lock:
            self._clock = ScaledClock(start)
            self._sequence = SwitchSequence(events)
            self.changes, self.records, self._pending = [], [], []
            for e in events:
                self._watched.setdefault(e.pin, False)

    def disarm(self) -> list[SwitchEvent]:
        """Stop switching; return the events that did not happen."""
        with self._lock:
            left = self._sequence.pending if self._sequence is not None else []
            self._clock = self._sequence = None
        self._publish_pace()
        return left

    @contextmanager
    def hold(self, until: float) -> Iterator[None]:
        """A paced ur_sim does not run past robot time ``until`` [s] inside this block (for a goal on its way that
        starts after it); without a pace topic this does nothing."""
        with self._lock:
            self._holds.append(until)
        self._publish_pace()
        try:
            yield
        finally:
            with self._lock:
                self._holds.remove(until)
            self._publish_pace()

    def _on_state(self, msg: JointTrajectoryControllerState) -> None:
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        with self._lock:
            last, self._last_stamp = self._last_stamp, stamp
            if self._clock is None:
                return
            if last is not None and 0.0 < stamp - last < 0.1:
                self._sequence.half_period = 0.5 * (stamp - last)
            if self._uses_robot_scaling:
                # Published in the same cycle as this state (a cycle apart at most: the subscriptions are separate).
                factor = self._robot_factor if self._robot_factor is not None else 1.0
            else:
                factor = msg.speed_scaling_factor
            t = self._clock.update(stamp, factor)
            due = self._sequence.due(t)
        for event in due:
            future = self.client.call_async(SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=event.pin,
                                                          state=1.0 if event.state else 0.0))
            self._pending.append((event, stamp, t, future))
            future.add_done_callback(lambda _: self._publish_pace())
        self._publish_pace()

    def robot_time(self, stamp: float) -> None:
        """The robot's time [s] of a joint state: paced, it is the newest time while no goal is armed (joint states
        come every cycle, controller states only while the controller is active)."""
        self._last_joint_state = stamp
        if self._clock is None:
            self._publish_pace()

    def follow_joint_states(self, on_joint_state) -> None:
        """Paced: take the robot's time from every joint state the client receives; `on_joint_state` registers a
        listener on the client's one subscription (:meth:`URClient.on_joint_state`)."""
        on_joint_state(lambda sample: self.robot_time(sample.t))

    def _publish_pace(self) -> None:
        """Tell a paced ur_sim how far it may run: ``FREE_AHEAD`` past the newest robot time this client handled
        (controller state while a goal is armed, else joint state), but not past the earliest robot time of the next
        switch (its trajectory time after the goal's start: the scaled controller's clock runs at most at the robot's
        pace), and not past the stamp of a switch call not answered yet."""
        newest = self._last_joint_state if self._clock is None else self._last_stamp
        if self._pace is None:
            return
        if newest is None:
            return

        hold = newest + FREE_AHEAD
        clock, sequence = self._clock, self._sequence
        if clock is not None and sequence is not None and sequence.pending:
            due = clock.start + min(e.t for e in sequence.pending) - 4.0 * sequence.half_period
            hold = min(hold, max(newest, due))
        hold = min([hold] + [s for _, s, _, f in self._pending if not f.done()] + list(self._holds))
        # A message per change of half of FREE_AHEAD at most, and every held-back one: each message wakes ur_sim's
        # executor, and one per cycle cost it a third of its time.
        last = self._pace_sent
        if last is not None and last <= hold < last + 0.5 * FREE_AHEAD and hold >= newest + FREE_AHEAD - 1e-9:
            return
        self._pace_sent = hold
        sec = int(hold // 1)
        self._pace.publish(Clock(clock=Time(sec=sec, nanosec=int(round((hold - sec) * 1e9)) % 1_000_000_000)))

    @property
    def robot_factor(self) -> float | None:
        """The robot's speed scaling [0, 1] last received (None: not received yet, or not this clock's factor)."""
        return self._robot_factor

    def _on_robot_scaling(self, msg: Float64) -> None:
        with self._lock:
            self._robot_factor = msg.data / 100.0

    def _on_io(self, msg: IOStates) -> None:
        with self._lock:
            for pin, known in list(self._watched.items()):
                if pin < len(msg.digital_out_states) and bool(msg.digital_out_states[pin].state) != known:
                    self._watched[pin] = not known
                    stamp = self._last_stamp if self._last_stamp is not None else float('nan')
                    self.changes.append(OutputChange(pin, not known, stamp,
                                                     self._clock.now if self._clock is not None else None))

    def collect(self) -> list[SwitchRecord]:
        """Records of every call so far (answers that arrived are filled in)."""
        for event, stamp, t, future in self._pending:
            ok = future.result().success if future.done() and future.result() is not None else None
            self.records.append(SwitchRecord(event, stamp, t, ok))
        self._pending = []
        return list(self.records)

    def off(self, pin: int, timeout: float = 5.0, resend: float = 1.0) -> bool:
        """Switch ``pin`` off now and wait for the answer (any armed events are dropped first).

        A request not answered within ``resend`` [s] is sent again (switching off twice does no harm; see
        service_call.py). Raises ClientError when nothing answers within ``timeout`` [s].
        """
        self.disarm()
        request = SetIO.Request(fun=SetIO.Request.FUN_SET_DIGITAL_OUT, pin=pin, state=0.0)
        return bool(call_idempotent(self.client, request, f'switching pin {pin} off', timeout, resend).success)


def dispenser_for(node: Node, prefix: str, controller: str, pace_topic: str | None = None) -> DispenserIO:
    """The gun switched on the clock of trajectory controller `controller` under namespace `prefix` ('' or '/ns');
    `pace_topic`: keep a ur_sim started with that pace_topic in step with it (then call
    :meth:`DispenserIO.follow_joint_states`)."""
    robot = None if controller == PLAIN_CONTROLLER else f'{prefix}/speed_scaling_state_broadcaster/speed_scaling'
    return DispenserIO(node, f'{prefix}/{controller}/controller_state', robot, pace_topic)
