"""The link between the simulation process and the trajectory controller's interface process.

The trajectory controllers' action servers and joint_trajectory subscriptions live in a process of their own
(``trajectory_gateway.py``), so that receiving and converting a large trajectory (rclpy takes an action goal in
C while holding the GIL: about 0.1 s per 100,000 points here even read straight into arrays, ``goal_intake.py``)
never stops the simulation loop, which must publish every 2 ms. The two processes exchange the small messages
below over a pipe, in order:

* gateway -> simulation: :class:`Start` (a validated trajectory, in the sender's joint order), :class:`Cancel`,
  :class:`Dropped` (a joint_trajectory message refused), :class:`Ack` (an :class:`Activation` has been applied);
* simulation -> gateway: :class:`Ended` (a goal's outcome), :class:`Canceled` (the answer to a Cancel),
  :class:`Feedback`, :class:`Gate` (whether the robot may take commands now), :class:`Activation` (a controller
  was switched by the controller manager).

One gateway process serves every trajectory controller (each a node of its own there); Start, Cancel and
Activation name the controller, the other messages follow the goal's token.

The simulated time is shared through a double in shared memory, written by the simulation every cycle and read
by the gateway's validation (stamps in the past, stamps far in the future).

The gateway is started as ``python -m ur_sim_driver.gateway.trajectory_gateway`` with the pipe (a socket pair) and the
shared memory (a memfd) handed over as file descriptors, not through multiprocessing's spawn, which re-imports
the caller's main module: a user's plain script that builds a UrSimNode without an ``if __name__`` guard would
start itself again.
"""
from __future__ import annotations

import collections
import mmap
import os
import queue
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from multiprocessing.connection import Connection

import numpy as np

from ur_sim_driver.motion.command_arrays import CommandArrays
from ur_sim_driver.motion.passthrough import PassthroughTolerances
from ur_sim_driver.motion.trajectory_types import SegmentTolerances

ENDED_KEPT = 1024  # how many ended goals' tokens GatewayLink.ended keeps


@dataclass(frozen=True)
class GatewayConfig:
    """What the gateway process needs to serve the controllers' interfaces (picklable).

    Attributes:
        controllers: the trajectory controllers' names (each its own node, as in ros2_control).
        active: the names of those active at start.
        namespace: namespace of every interface ('' or '/ur10').
        joints: n controller joint names (with the tf_prefix).
        q_min, q_max, v_max: (n,) joint limits [rad], [rad/s], used only with `strict_limits`.
        strict_limits: reject positions outside the limits and velocities above them (stricter than upstream).
        allow_partial: upstream allow_partial_joints_goal.
        allow_nonzero_end_velocity: upstream allow_nonzero_velocity_at_trajectory_end.
        defaults: the controller's default tolerances (resolved with each goal's in the gateway).
        passthrough: the controllers among `controllers` served with passthrough_trajectory_controller's rules
            (``passthrough.py``; no joint_trajectory topic).
    """

    controllers: tuple[str, ...]
    active: tuple[str, ...]
    namespace: str
    joints: tuple[str, ...]
    q_min: np.ndarray
    q_max: np.ndarray
    v_max: np.ndarray
    strict_limits: bool
    allow_partial: bool
    allow_nonzero_end_velocity: bool
    defaults: SegmentTolerances
    passthrough: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class Start:
    """Replace `controller`'s active trajectory. `token` names an action goal; None for a topic message.
    `tolerances` are a passthrough controller's ``PassthroughTolerances``."""

    token: bytes | None
    command: CommandArrays
    tolerances: SegmentTolerances | PassthroughTolerances | None
    controller: str = ''


@dataclass(frozen=True)
class Cancel:
    """The client asked `controller` to cancel goal `token`."""

    token: bytes
    controller: str = ''


@dataclass(frozen=True)
class Dropped:
    """`controller`'s joint_trajectory message was refused (logged by the gateway with its reason): the simulation
    counts it with the messages it received, so that each message has one known end."""

    controller: str = ''


@dataclass(frozen=True)
class Activation:
    """`controller` was activated (`active`) or deactivated; the gateway answers :class:`Ack` with `seq`."""

    controller: str
    active: bool
    seq: int


@dataclass(frozen=True)
class Ack:
    """The gateway applied the :class:`Activation` numbered `seq`."""

    seq: int


@dataclass(frozen=True)
class Ended:
    """Goal `token` ended with `code` (control_msgs result code) and `message`; `aborted` ends it aborted even
    with code 0 (SUCCESSFUL), as upstream's passthrough controller does when the robot aborts the trajectory."""

    token: Hashable
    code: int
    message: str
    aborted: bool = False


@dataclass(frozen=True)
class Canceled:
    """Answer to :class:`Cancel`: `ok` when the goal was still active and now holds."""

    token: bytes
    ok: bool


@dataclass(frozen=True, eq=False)
class Feedback:
    """One FollowJointTrajectory feedback: time [s] and (n,) desired/actual/error arrays."""

    token: bytes
    t: float
    desired: tuple[np.ndarray, np.ndarray, np.ndarray]
    actual: tuple[np.ndarray, np.ndarray]
    error: tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class Gate:
    """The robot cannot move (`reason` names its state) or can again (None): goals and messages are refused
    while a reason is set, as the driver's controller_stopper leaves the controller inactive."""

    reason: str | None


STOP = 'stop'  # sent last: the gateway ends its goals and exits


class GatewayLink:
    """The simulation side: starts the gateway process, receives from it in a thread, sends from another.

    Args:
        config: the gateway's configuration.
        on_message: called in the receiving thread for every :class:`Start` and :class:`Cancel`.
    """

    _seq = 0

    def __init__(self, config: GatewayConfig, on_message: Callable[[object], None]) -> None:
        parent_end, child_end = socket.socketpair()
        time_fd = os.memfd_create('ur_sim_time')
        os.ftruncate(time_fd, 8)
        self._time = mmap.mmap(time_fd, 8)
        self.process = subprocess.Popen(
            [sys.executable, '-m', 'ur_sim_driver.gateway.trajectory_gateway', str(child_end.fileno()), str(time_fd)],
            # Its own session: a Ctrl-C (or a test's SIGINT to ur_sim's process group) must not interrupt it while
            # it imports; ur_sim stops it through the pipe, and it exits on its own when the pipe closes.
            pass_fds=(child_end.fileno(), time_fd), start_new_session=True)
        child_end.close()
        os.close(time_fd)
        self._conn = Connection(parent_end.detach())
        self._conn.send(config)
        self._on_message = on_message
        self._outbox: queue.SimpleQueue = queue.SimpleQueue()
        self._closed = threading.Event()
        self._acks: dict[int, threading.Event] = {}
        self._acks_lock = threading.Lock()
        # Tokens of the latest goals the simulation ended (Ended, or a granted Canceled), newest last: a script that
        # steps the simulation itself steps until its goal is among them, then waits for the result's delivery.
        self.ended: collections.deque = collections.deque(maxlen=ENDED_KEPT)
        self._receiver = threading.Thread(target=self._receive, name='gateway_receive', daemon=True)
        self._sender = threading.Thread(target=self._send, name='gateway_send', daemon=True)
        self._receiver.start()
        self._sender.start()

    def set_sim_time(self, t: float) -> None:
        """Publish the simulated time [s] to the gateway (every control cycle)."""
        struct.pack_into('d', self._time, 0, t)

    def send(self, message: object) -> None:
        """Queue a message for the gateway; never blocks (the simulation loop calls this)."""
        if isinstance(message, Ended) or (isinstance(message, Canceled) and message.ok):
            self.ended.append(message.token)
        self._outbox.put(message)

    @property
    def settled(self) -> bool:
        """True once the gateway has applied every activation sent to it (a goal sent now meets those states)."""
        with self._acks_lock:
            return not self._acks

    def activation(self, controller: str, active: bool) -> threading.Event:
        """Tell the gateway that `controller` was switched; the event is set once it has applied that."""
        event = threading.Event()
        with self._acks_lock:
            self._seq += 1
            seq = self._seq
            self._acks[seq] = event
        self.send(Activation(controller, active, seq))
        return event

    def _send(self) -> None:
        while True:
            message = self._outbox.get()
            try:
                self._conn.send(message)
            except (OSError, EOFError, BrokenPipeError):
                return
            if message is STOP:
                return

    def _receive(self) -> None:
        while not self._closed.is_set():
            try:
                message = self._conn.recv()
            except (OSError, EOFError):
                return
            if isinstance(message, Ack):
                with self._acks_lock:
                    event = self._acks.pop(message.seq, None)
                if event is not None:
                    event.set()
                continue
            self._on_message(message)

    def close(self, timeout: float = 5.0) -> None:
        """Stop the gateway process (it ends its goals as aborted) and the threads."""
        self._closed.set()
        self._outbox.put(STOP)
        self._sender.join(timeout=timeout)
        try:
            self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.process.terminate()
            self.process.wait(timeout=timeout)
        self._receiver.join(timeout=timeout)  # the child's end is closed now: recv() has seen EOF
        self._conn.close()
        self._time.close()
