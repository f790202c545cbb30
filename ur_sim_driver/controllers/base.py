"""The lifecycle every emulated controller and driver node of ur_sim follows: ros2_control's, reduced.

In the real driver each controller is a node named after itself, loaded by the controller manager, which
configures it, activates it and then calls ``update`` from its control loop. ur_sim mirrors that: a
:class:`Component` creates its ROS interfaces on its own rclpy node in :meth:`Component.configure`, is switched
with :meth:`activate` / :meth:`deactivate`, and :meth:`update` is called from the simulation loop once per
control cycle while it is active, with a :class:`Cycle` (what was measured and commanded in that cycle).

``update`` runs in the simulation thread outside the simulation lock: it reads the Cycle and publishes. A
component that changes the simulation (IO, payload, robot state) does so from its service callbacks under
``host.lock``, and keeps that short: the loop needs the lock every cycle.
"""
from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from builtin_interfaces.msg import Time
from rclpy.node import Node

from ur_sim_driver.motion.conversions import RobotClock
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.physics.physics import ArmState

if TYPE_CHECKING:  # imported for annotations only: no import cycle with the node
    from ur_sim_driver.robot.dashboard_server import DashboardServer
    from ur_sim_driver.robot.robot_state import RobotState
    from ur_sim_driver.robot.sim_config import SimConfig
    from ur_sim_driver.robot.simulator import Simulator
    from ur_sim_driver.robot.speed_scaling import RobotSpeedScaling
    from ur_sim_driver.urscript.runner import ScriptRunner


@dataclass(frozen=True, eq=False)
class Cycle:
    """One control cycle as the controllers see it.

    Attributes:
        index: cycle counter since start.
        t: simulated time at the start of the cycle [s] (the time of `state`).
        stamp_parts: `t` as (sec, nanosec), as builtin_interfaces/Time splits it.
        state: joint state measured at the start of the cycle.
        reference: the trajectory controller's reference for this cycle.
        effort: (n,) torques applied during the cycle [N m].
        robot_factor: the robot's own speed scaling in [0, 1] (speed slider x its slowdowns).
        tcp_position: (3,) tool0 in the base frame [m], at `t`.
        tcp_orientation: (4,) tool0 orientation in the base frame, quaternion (x, y, z, w).
        wrench: (6,) force [N] and torque [N m] of the flange's force-torque sensor in tool0_controller
            (``Simulator.wrench``), as of the last physics step.
    """

    index: int
    t: float
    stamp_parts: tuple[int, int]
    state: ArmState
    reference: TrajectorySample
    effort: np.ndarray
    robot_factor: float
    tcp_position: np.ndarray
    tcp_orientation: np.ndarray
    wrench: np.ndarray

    @cached_property
    def stamp(self) -> Time:
        """`t` as a builtin_interfaces/Time, made when first asked for (shared: do not modify)."""
        sec, nanosec = self.stamp_parts
        return Time(sec=sec, nanosec=nanosec)


@dataclass
class Host:
    """What ur_sim gives every component at configure time.

    Attributes:
        cfg: the node's validated configuration.
        sim: the simulated arm (touch it only under `lock`).
        lock: the simulation lock.
        robot: the robot's modes and program state (under `lock`).
        speed_scaling: the robot's own speed scaling (under `lock`).
        context: the rclpy context every component node lives in.
        robot_files: the robot's file system (flight reports, support files), a directory of this run.
        dashboard: the robot's dashboard command interpreter, one for the ROS services and the TCP port (under
            `lock`).
        scripts: the controller's URScript program slot (under `lock`).
        clock: simulated time <-> stamps (``conversions.RobotClock``): every stamp a component sends or reads.
    """

    cfg: SimConfig
    sim: Simulator
    lock: threading.Lock
    robot: RobotState
    speed_scaling: RobotSpeedScaling
    context: object
    robot_files: Path | None = None
    dashboard: DashboardServer | None = None
    scripts: ScriptRunner | None = None
    clock: RobotClock = RobotClock()
    # Conditions a service callback waits for, each with the event the loop sets once it holds (under `lock`).
    _waiters: list[tuple[Callable[[], bool], threading.Event]] = field(default_factory=list)

    def when(self, condition: Callable[[], bool]) -> threading.Event:
        """An event the simulation loop sets at the end of the first cycle after which `condition()` (evaluated under
        the lock) holds: a service that waits for the robot waits on it, and waits for exactly the cycles it needs."""
        event = threading.Event()
        with self.lock:
            if condition():
                event.set()
            else:
                self._waiters.append((condition, event))
        return event

    def forget(self, event: threading.Event) -> None:
        """Stop checking the condition of `event` (its waiter gave up)."""
        with self.lock:
            self._waiters[:] = [(c, e) for c, e in self._waiters if e is not event]

    @property
    def waiting(self) -> bool:
        """A service callback waits for the robot (a script that steps the simulation itself steps then)."""
        return bool(self._waiters)

    def check_waiters(self) -> None:
        """Under the lock, at the end of a cycle: set the events whose conditions hold."""
        if self._waiters:
            remaining = []
            for condition, event in self._waiters:
                if condition():
                    event.set()
                else:
                    remaining.append((condition, event))
            self._waiters[:] = remaining

    def create_node(self, name: str, parameter_services: bool = False) -> Node:
        """A node named `name` in ur_sim's namespace, as ros2_control gives each controller one. With
        `parameter_services`, its parameters can be listed and set from outside, also undeclared ones (as the
        controller manager's node allows)."""
        ns = self.cfg.namespace.strip('/')
        return Node(name, namespace=f'/{ns}' if ns else '/', context=self.context,
                    start_parameter_services=parameter_services, allow_undeclared_parameters=parameter_services)


def destroy_node(node: Node) -> None:
    """Destroy `node` and its action servers and clients: rclpy's destroy_node leaves those alive, and each keeps
    the node (and its name in the graph of whoever shares its DDS participant) alive until it is destroyed itself."""
    for waitable in list(node.waitables):
        destroy = getattr(waitable, 'destroy', None)
        if destroy is not None:
            destroy()
    node.destroy_node()


def unload_node(node: Node, timeout: float = 5.0) -> None:
    """Take `node` out of the executor spinning it, then destroy it (a controller unloaded at run time).

    rclpy's executor builds each wait set from a snapshot of its nodes taken at the top of an iteration, and a
    waitable destroyed between the snapshot and the build raises InvalidHandle in the spinning thread. So after
    ``remove_node`` this waits for two no-op tasks, the second created once the first has run: the second is taken
    up in an iteration that began after the removal, so no wait set with the node's entities is built any more.
    """
    executor = node.executor
    if executor is not None:
        executor.remove_node(node)
        for _ in range(2):
            ran = threading.Event()
            executor.create_task(ran.set)
            if not ran.wait(timeout):  # not spinning (shutting down): nothing builds wait sets
                break
    destroy_node(node)


class Component:
    """Base class of an emulated controller or driver node.

    Subclasses set :attr:`name` (the controller's name, e.g. ``io_and_status_controller``) and
    :attr:`type_name` (its plugin type, e.g. ``ur_controllers/GPIOController``) and override the hooks.
    """

    name: str = ''
    type_name: str = ''
    initially_active: bool = True  # the driver's launch file starts it active
    # A ros2_control controller (listed and switched by the controller manager); False for the driver's other
    # nodes (dashboard client, robot_state_publisher) and ur_sim's own simulation-only ones.
    is_controller: bool = True

    def __init__(self) -> None:
        self.node: Node | None = None
        self.host: Host | None = None
        self.active = False

    def configure(self, host: Host) -> None:
        """Create the node and the ROS interfaces (they exist while inactive, as with a loaded controller)."""
        self.host = host
        self.node = host.create_node(self.name)
        self.on_configure(host, self.node)

    def activate(self) -> None:
        """Start updating (and publishing)."""
        self.on_activate()
        self.active = True

    def deactivate(self) -> None:
        """Stop updating."""
        self.active = False
        self.on_deactivate()

    def destroy(self) -> None:
        """Release the node (ur_sim is shutting down)."""
        if self.node is not None:
            destroy_node(self.node)
            self.node = None

    def unload(self) -> None:
        """Release the node while the executor spins (unload_controller)."""
        if self.node is not None:
            unload_node(self.node)
            self.node = None

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """(command interfaces it claims while active, state interfaces it reads), with the tf_prefix, as
        list_controllers reports them; the controller manager refuses two claims of one command interface."""
        return (), ()

    # ---- hooks ---------------------------------------------------------------------------------
    def on_configure(self, host: Host, node: Node) -> None:
        """Create publishers, services and subscriptions on `node`."""

    def on_activate(self) -> None:
        """Called before the first update after a switch to active."""

    def on_deactivate(self) -> None:
        """Called after the last update."""

    def update(self, cycle: Cycle) -> None:
        """One control cycle (simulation thread, outside the lock)."""
