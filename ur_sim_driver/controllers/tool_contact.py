"""tool_contact_controller: ``~/detect_tool_contact`` (ur_msgs/action/ToolContact).

Upstream (ur_controllers' ToolContactController with the UR client library's startToolContact): while a goal is
active the robot watches its tool; when the tool touches something, the robot cancels every motion, and the
goal succeeds (the controller then ends tool-contact mode, so the robot takes commands again). The action carries
no data: the outcome is the goal's status. Facts kept from upstream: goals are rejected while the controller is
inactive and while a goal is active; cancel ends the goal canceled; deactivation aborts it; the controller
claims only ``<tf_prefix>tool_contact/tool_contact_set_state``, so it runs beside a trajectory or forward
controller (``ur_hardware.py``); CB3 robots refuse it.

How ur_sim detects the contact: after every control cycle, a contact of a body of the tool or the flange (the
subtree of ``wrist_3_link``) whose force, averaged over the cycle's physics steps (``physics.py``), is above
:data:`TOOL_CONTACT_FORCE` (or half the protective stop force when that is lower). The protective stop acts on a
mean over a longer window (``safety.py``), so that a slow approach ends in a tool contact, never in a protective
stop (``test_tool_contact.py``: 20 approaches at 5 to 50 mm/s). The stop
is commanded in the next control cycle: the active joint controller holds the measured position and its goal
ends (``JointCommander.halt``), and the servo brakes at the robot's limits.
"""
from __future__ import annotations

import threading
import time

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from ur_msgs.action import ToolContact

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.ur_hardware import TOOL_CONTACT
from ur_sim_driver.physics.physics import Contact
from ur_sim_driver.physics.tool_contact import TOOL_CONTACT_FORCE, strongest_touch
from ur_sim_driver.robot.sim_config import SimConfig

TYPE = 'ur_controllers/ToolContactController'
# Upstream's log lines.
INACTIVE = 'Tool contact controller is not in active state, can not accept action goals.'
BUSY = 'Tool contact already active, rejecting goal.'
DEACTIVATED = 'Aborting tool contact, as controller has been deactivated.'
CB3 = 'This feature is not supported on CB3 robots, controller will not be started.'
SUCCEEDED, ABORTED, CANCELED = 'succeeded', 'aborted', 'canceled'


CANCEL_TAKEN = 1.0  # [s] of wall time for rclpy to take a cancel this controller has already carried out


class _Goal:
    """One accepted goal: its outcome is decided by the simulation loop, the execute callback reports it."""

    def __init__(self, handle) -> None:
        self.handle = handle
        self.outcome: str | None = None
        self.done = threading.Event()


class ToolContactController(Component):
    """The driver's tool_contact_controller."""

    name = 'tool_contact_controller'
    type_name = TYPE
    initially_active = False

    def __init__(self) -> None:
        super().__init__()
        self._goal: _Goal | None = None  # the active goal (under the lock)
        self._unclaimed: _Goal | None = None  # the goal accepted last, until its execution takes it
        self._tool_bodies: frozenset[str] = frozenset()
        self._threshold = TOOL_CONTACT_FORCE
        self.unavailable: str | None = None
        self.last_contact: tuple[float, Contact] | None = None  # (time [s], contact) of the last detection

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        p = f'{cfg.tf_prefix}{TOOL_CONTACT}'
        return (f'{p}/tool_contact_set_state',), (f'{p}/tool_contact_result',
                                                  f'{cfg.tf_prefix}get_robot_software_version/get_version_major',
                                                  f'{p}/tool_contact_state')

    def on_configure(self, host: Host, node: Node) -> None:
        if host.sim.params.series == 'cb3':
            self.unavailable = CB3
        self._tool_bodies = host.sim.tool_bodies
        self._threshold = host.sim.tool_contact_force
        self._server = ActionServer(
            node, ToolContact, host.cfg.prefixed(f'{self.name}/detect_tool_contact'), execute_callback=self._execute,
            goal_callback=self._on_goal, cancel_callback=self._on_cancel, callback_group=ReentrantCallbackGroup())

    # ---- simulation loop, under the lock ---------------------------------------------------------------------
    @property
    def watching(self) -> bool:
        """A goal is active: contacts of the tool end it."""
        goal = self._goal
        return self.active and goal is not None and goal.outcome is None

    def detect(self, contacts: tuple[Contact, ...], t: float) -> str | None:
        """After a physics step at time `t` [s]: why the robot cancels its motion now (a tool contact), or None."""
        if not self.watching:
            return None
        c = strongest_touch(contacts, self._tool_bodies, self._threshold)
        if c is None:
            return None
        self.last_contact = (t, c)
        self._end(SUCCEEDED)
        return (f'tool contact: {c.robot_part} touched {c.other} ({c.force:.1f} N > {self._threshold:.1f} N); '
                'the robot cancelled the motion')

    def on_deactivate(self) -> None:
        if self._goal is not None and self._goal.outcome is None:
            self.node.get_logger().info(DEACTIVATED)
            self._end(ABORTED)

    def _end(self, outcome: str) -> None:
        goal = self._goal
        if goal is not None and goal.outcome is None:
            goal.outcome = outcome
            self._goal = None
            goal.done.set()

    # ---- action server (executor threads) -----------------------------------------------------------------------
    def _on_goal(self, goal_request) -> GoalResponse:
        self.node.get_logger().info('New goal received.')
        with self.host.lock:
            if not self.active:
                reason = INACTIVE
            elif self._goal is not None:
                reason = BUSY
            else:
                reason = None
                # reserved until accepted: a second goal meanwhile is refused
                self._goal = self._unclaimed = _Goal(None)
        if reason is not None:
            self.node.get_logger().error(reason)
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _on_cancel(self, goal_handle) -> CancelResponse:
        with self.host.lock:
            goal = self._goal
            # A cancel may come between the goal's acceptance and its execution, while the goal has no handle yet
            # (the trajectory_until_node cancels both its goals at once): it is this goal, as goals come one at a
            # time. Ignoring it left the execution waiting for ever.
            if goal is not None and goal.handle in (goal_handle, None) and goal.outcome is None:
                self.node.get_logger().info('Cancel tool contact requested.')
                self._end(CANCELED)
        return CancelResponse.ACCEPT

    def _cancel_taken(self, goal_handle) -> bool:
        """Whether rclpy has moved the goal to CANCELING (waited for up to CANCEL_TAKEN [s] of wall time). The
        cancel callback ends the goal at once, so that no contact ends it meanwhile, but rclpy takes the cancel only
        after the callback has returned ACCEPT: this execution, woken by the callback, could call canceled() first,
        an invalid transition that aborted the goal (seen once in a suite run)."""
        deadline = time.monotonic() + CANCEL_TAKEN
        while not goal_handle.is_cancel_requested and time.monotonic() < deadline and self.host.context.ok():
            time.sleep(0.001)  # a poll: rclpy offers no event for the goal's state
        return goal_handle.is_cancel_requested

    def _execute(self, goal_handle) -> ToolContact.Result:
        with self.host.lock:
            goal, self._unclaimed = self._unclaimed, None
            if goal is not None:  # cancelled or deactivated since its acceptance: its outcome is set
                goal.handle = goal_handle
            else:  # no goal of ours: nothing will end it, it ends here
                goal = _Goal(goal_handle)
                goal.outcome = ABORTED
                goal.done.set()
        self.node.get_logger().info('Goal accepted.')
        while not goal.done.wait(0.05):
            if not self.host.context.ok():
                goal.outcome = ABORTED
                break
        if goal.outcome == SUCCEEDED:
            self.node.get_logger().info('Tool contact finished successfully.')
            goal_handle.succeed()
        elif goal.outcome == CANCELED and self._cancel_taken(goal_handle):
            goal_handle.canceled()
        else:
            goal_handle.abort()
        return ToolContact.Result()
