"""The link between the simulation process and the trajectory controller's interface process.

The trajectory controllers' action servers and joint_trajectory subscriptions live in a process of their own
(``gateway_process.py``, one ``trajectory_gateway.py`` per controller), so that receiving and converting a large
trajectory (rclpy takes an action goal in C while holding the GIL: about 0.1 s per 100,000 points here even read
straight into arrays, ``goal_intake.py``) never stops the simulation loop, which must publish every 2 ms. The gateway's
job is intake: it takes goals and messages in, converts and validates them, and owns the action goals' handles until
they end. Everything about the robot and the controllers (which is active, whether the robot can move, the simulated
time) is owned by the simulation and asked for, never copied: the two processes exchange the small messages below over
one pipe, in order:

* gateway -> simulation: :class:`Admit` (may this controller take a goal or message now?), :class:`Start` (a
  validated trajectory, in the sender's joint order), :class:`Cancel`, :class:`Dropped` (a joint_trajectory
  message refused);
* simulation -> gateway: :class:`Admission` (the answer to Admit, with the simulated time), :class:`Ended` (a
  goal's outcome), :class:`Canceled` (the answer to a Cancel), :class:`Feedback`.

One gateway process serves every trajectory controller from one node of its own (``ur_sim_trajectory_gateway``:
the controllers' nodes are ur_sim's); Admit, Start and Cancel name the controller, the other messages follow the
request or the goal's token.

The gateway is started as ``python -m ur_sim_driver.gateway.gateway_process`` with the pipe (a socket pair)
handed over as a file descriptor, not through multiprocessing's spawn, which re-imports the caller's main module:
a user's plain script that builds a UrSimNode without an ``if __name__`` guard would start itself again.
"""
from __future__ import annotations

import collections
import queue
import socket
import subprocess
import sys
import threading
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from multiprocessing.connection import Connection

import numpy as np

from ur_sim_driver.motion.command_arrays import CommandArrays
from ur_sim_driver.motion.conversions import RobotClock
from ur_sim_driver.motion.passthrough import PassthroughTolerances
from ur_sim_driver.motion.trajectory_types import SegmentTolerances

ENDED_KEPT = 1024  # how many ended goals' tokens GatewayLink.ended keeps


@dataclass(frozen=True)
class GatewayConfig:
    """What the gateway process needs to serve the controllers' interfaces (picklable).

    Attributes:
        controllers: the trajectory controllers' names (their interfaces are named after them, as in ros2_control).
        namespace: namespace of every interface ('' or '/ur10').
        joints: n controller joint names (with the tf_prefix).
        q_min, q_max, v_max: (n,) joint limits [rad], [rad/s], used only with `strict_limits`.
        strict_limits: reject positions outside the limits and velocities above them (stricter than upstream).
        allow_partial: upstream allow_partial_joints_goal.
        allow_nonzero_end_velocity: upstream allow_nonzero_velocity_at_trajectory_end.
        defaults: the controller's default tolerances (resolved with each goal's in the gateway).
        passthrough: the controllers among `controllers` served with passthrough_trajectory_controller's rules
            (``passthrough.py``; no joint_trajectory topic).
        clock: the stamps' origin (ur_sim's; the gateway converts the stamps it receives and sends with it).
    """

    controllers: tuple[str, ...]
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
    clock: RobotClock = RobotClock()


@dataclass(frozen=True, eq=False)
class Start:
    """Replace `controller`'s active trajectory. `token` names an action goal; None for a topic message.
    `tolerances` are a passthrough controller's ``PassthroughTolerances``."""

    token: bytes | None
    command: CommandArrays
    tolerances: SegmentTolerances | PassthroughTolerances | None
    controller: str = ''


@dataclass(frozen=True)
class Received:
    """The simulation has goal `token` in its controller (or has ended it): the gateway reports the goal executing
    only then, so a client that sees it executing knows the controller has it."""

    token: bytes


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
class Admit:
    """May `controller` take a goal (or, with `topic`, a joint_trajectory message) now? Answered by :class:`Admission`
    with the same `request` number."""

    request: int
    controller: str
    topic: bool = False


@dataclass(frozen=True)
class Admission:
    """The answer to :class:`Admit` `request`: None, or why the controller refuses (in upstream's words); and the
    simulated time [s] when it was decided (for the validation of stamps)."""

    request: int
    reason: str | None
    now: float


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
    desired_time: float = 0.0  # [s] desired.time_from_start: trajectory time since the trajectory's start
    actual_time: float = 0.0  # [s] actual.time_from_start: time since the trajectory's start


STOP = 'stop'  # sent last: the gateway ends its goals and exits


class GatewayLink:
    """The simulation side: starts the gateway process, receives from it in a thread, sends from another.

    Args:
        config: the gateway's configuration.
        on_message: called in the receiving thread for every message from the gateway.
    """

    def __init__(self, config: GatewayConfig, on_message: Callable[[object], None]) -> None:
        parent_end, child_end = socket.socketpair()
        self.process = subprocess.Popen(
            [sys.executable, '-m', 'ur_sim_driver.gateway.gateway_process', str(child_end.fileno())],
            # Its own session: a Ctrl-C (or a test's SIGINT to ur_sim's process group) must not interrupt it while
            # it imports; ur_sim stops it through the pipe, and it exits on its own when the pipe closes.
            pass_fds=(child_end.fileno(),), start_new_session=True)
        child_end.close()
        self._conn = Connection(parent_end.detach())
        self._conn.send(config)
        self._on_message = on_message
        self._outbox: queue.SimpleQueue = queue.SimpleQueue()
        self._closed = threading.Event()
        # Tokens of the latest goals the simulation ended (Ended, or a granted Canceled), newest last: a script that
        # steps the simulation itself steps until its goal is among them, then waits for the result's delivery.
        self.ended: collections.deque = collections.deque(maxlen=ENDED_KEPT)
        self._receiver = threading.Thread(target=self._receive, name='gateway_receive', daemon=True)
        self._sender = threading.Thread(target=self._send, name='gateway_send', daemon=True)
        self._child_closed = threading.Event()  # the process's end of the pipe is closed (recv() saw EOF)
        self._receiver.start()
        self._sender.start()

    def send(self, message: object) -> None:
        """Queue a message for the gateway; never blocks (the simulation loop calls this)."""
        if isinstance(message, Ended) or (isinstance(message, Canceled) and message.ok):
            self.ended.append(message.token)
        self._outbox.put(message)

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
        try:
            while True:
                message = self._conn.recv()
                if not self._closed.is_set():  # after close, only drained until the process lets go of the pipe
                    self._on_message(message)
        except (OSError, EOFError):
            pass
        finally:
            self._child_closed.set()

    def close(self, timeout: float = 5.0) -> None:
        """Stop the gateway process (it ends its goals as aborted) and the threads.

        Returns once the process has closed its end of the pipe, which it does last, after its goals' results went
        out and its node and ROS context are gone; its interpreter's exit after that (about 0.16 s of finalisation)
        is waited for by a thread of its own (every ur_sim stop of the suite waited for it)."""
        self._closed.set()
        self._outbox.put(STOP)
        self._sender.join(timeout=timeout)
        if self._child_closed.wait(timeout=timeout):
            threading.Thread(target=self.process.wait, name='gateway_reap', daemon=True).start()
        else:
            self.process.terminate()
            self.process.wait(timeout=timeout)
        self._receiver.join(timeout=timeout)
        self._conn.close()
