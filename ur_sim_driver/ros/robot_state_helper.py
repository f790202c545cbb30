"""``/ur_robot_state_helper``: the driver's robot_state_helper node, over the simulated robot.

``~/set_mode`` (ur_dashboard_msgs/action/SetMode) brings the robot to POWER_OFF, IDLE or RUNNING, recovering its
safety mode first and optionally stopping the program before and playing it after; the decisions are
``controllers/set_mode.py``'s. The robot commands go to the robot directly (upstream sends them through the primary
interface), the program is played as upstream plays it: resend_robot_program in ``headless_mode``, the dashboard's
play otherwise. Feedback carries the robot and safety modes whenever one changes while a goal runs. A goal waits
for its target in simulated time; cancel requests are refused, as upstream refuses them.
"""
from __future__ import annotations

import threading
import time

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from ur_dashboard_msgs.action import SetMode

from ur_sim_driver.controllers import set_mode
from ur_sim_driver.controllers.base import Component, Host

STALL_TIMEOUT = 10.0  # [s] of wall time without simulated time advancing: the simulation is not running


class RobotStateHelper(Component):
    """The SetMode action server (one goal at a time)."""

    name = 'ur_robot_state_helper'
    type_name = 'ur_robot_driver/robot_state_helper'  # a node of the driver, not a controller
    is_controller = False

    def on_configure(self, host: Host, node: Node) -> None:
        self._headless = bool(node.declare_parameter('headless_mode', host.cfg.headless_mode).value)
        self._busy = threading.Lock()
        self._server = ActionServer(node, SetMode, '~/set_mode', execute_callback=self._execute,
                                    goal_callback=lambda goal: GoalResponse.ACCEPT,
                                    cancel_callback=self._on_cancel, callback_group=ReentrantCallbackGroup())

    def _on_cancel(self, goal_handle) -> CancelResponse:
        self.node.get_logger().info('Received request to cancel goal')
        return CancelResponse.REJECT

    def _robot(self, command: str) -> str | None:
        """Run a robot command (a RobotState method) under the lock; None when done, else why not."""
        with self.host.lock:
            return getattr(self.host.robot, command)()

    def _execute(self, goal_handle) -> SetMode.Result:
        with self._busy:
            result = SetMode.Result()
            result.success, result.message = self._run(goal_handle, goal_handle.request)
            if result.success:
                goal_handle.succeed()
            else:
                goal_handle.abort()
            return result

    def _run(self, goal_handle, goal: SetMode.Goal) -> tuple[bool, str]:
        logger, robot = self.node.get_logger(), self.host.robot
        target = int(goal.target_robot_mode)
        refusal = set_mode.target_refusal(target)
        if refusal is not None:
            return False, refusal
        if goal.stop_program and robot.program_running:
            self._robot('stop')
        with self.host.lock:
            modes = robot.robot_mode, robot.safety_mode
        if set_mode.needs_transition(*modes, target):
            logger.info(f'Target mode was set to {set_mode.mode_name(target)}.')
            for step in (set_mode.safety_recovery(modes[1]), set_mode.mode_transition(modes[0], target)):
                if step.fails:
                    logger.warning(step.log)
                    return False, set_mode.TRANSITION_FAILED
                for command in step.commands:
                    reason = self._robot(command)
                    if reason is not None:
                        logger.warning(reason)
                        return False, set_mode.TRANSITION_FAILED
        if not self._wait_for(goal_handle, target):
            return False, (f'The simulation did not advance for {STALL_TIMEOUT:.0f} s: the robot did not reach '
                           f'{set_mode.mode_name(target)}')
        if target == set_mode.RUNNING and goal.play_program and not robot.program_running:
            reason = self._robot('resend_robot_program' if self._headless else 'play')
            if reason is not None:
                logger.error(reason)
                return False, set_mode.REACHED  # upstream answers the trigger's failure with this message
        return True, set_mode.REACHED

    def _wait_for(self, goal_handle, target: int) -> bool:
        """Wait in simulated time until the robot is in `target`, publishing feedback on every mode change; False
        when the simulation stops advancing."""
        host, robot = self.host, self.host.robot
        with host.lock:
            seen = (robot.robot_mode, robot.safety_mode)
        self._feedback(goal_handle, seen)
        while seen[0] != target:
            event = host.when(lambda last=seen: (robot.robot_mode, robot.safety_mode) != last)
            last_t, last_wall = host.sim.time, time.monotonic()
            try:
                while not event.wait(0.01):
                    if host.sim.time != last_t:
                        last_t, last_wall = host.sim.time, time.monotonic()
                    elif time.monotonic() - last_wall > STALL_TIMEOUT or not host.context.ok():
                        return False
            finally:
                host.forget(event)
            with host.lock:
                seen = (robot.robot_mode, robot.safety_mode)
            self.node.get_logger().info(f'The robot is currently in mode {set_mode.mode_name(seen[0])}.')
            self._feedback(goal_handle, seen)
        return True

    @staticmethod
    def _feedback(goal_handle, modes: tuple[int, int]) -> None:
        goal_handle.publish_feedback(SetMode.Feedback(current_robot_mode=modes[0], current_safety_mode=modes[1]))
