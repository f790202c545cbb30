"""passthrough_trajectory_controller: the whole trajectory goes to the robot, which interpolates it itself.

``~/follow_joint_trajectory`` is served by the gateway process like the trajectory controllers' actions (so a
large goal never stalls the loop), with the passthrough controller's rules (``passthrough.py``: all joints,
velocities and accelerations all or none, goal_tolerance for every joint or none, no goal while one runs) and
without a ``~/joint_trajectory`` topic (upstream has none). This side is the robot: it interpolates the points
as the UR does (``passthrough.robot_points``: quintic, cubic, or at rest at every point) with the trajectory
sampler of the JTC (``trajectory.py`` through ``jtc.TrajectoryController``, without its tolerance supervision),
stretched by the robot's own speed scaling, and runs the reference through the robot's servo, so the limits
hold. The robot reports the end once its servo is at the last point at rest; the goal is then judged as
upstream does (``passthrough.judge_end``). No feedback is published (upstream publishes none).

Cancel: the robot stops (holds the measured position, braking at its limits); the goal ends canceled.
Deactivation aborts the goal with upstream's words. A tool contact cancels the robot's trajectory: the goal
ends aborted with an empty result (error_code 0), as upstream's "aborted by hardware" branch does.
"""
from __future__ import annotations

import numpy as np

from ur_sim_driver.controllers.joint_command import JointCommandController
from ur_sim_driver.controllers.ur_hardware import PASSTHROUGH, joint_interfaces, prefixed_joints
from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway.gateway_link import Cancel, Canceled, Ended, GatewayLink, Start
from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.jtc import TrajectoryController
from ur_sim_driver.motion.passthrough import BUSY, DEACTIVATED, INACTIVE, PassthroughTolerances, judge_end, robot_points
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.motion.validation import map_to_config_order
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.sim_config import SimConfig

NAME = 'passthrough_trajectory_controller'
TYPE = 'ur_controllers/PassthroughTrajectoryController'
AT_REST = 1e-6  # [rad], [rad/s] the servo's setpoint this close to the last point, at rest, ends the motion


class _Goal:
    """The goal the robot executes."""

    def __init__(self, token: bytes, tol: PassthroughTolerances, final: np.ndarray, final_velocity, duration: float):
        self.token = token
        self.tol = tol
        self.final = final
        self.final_velocity = final_velocity
        self.duration = duration
        self.elapsed = 0.0


class PassthroughTrajectoryController(JointCommandController):
    """The driver's passthrough_trajectory_controller (inactive at start).

    Args:
        core: the robot's trajectory sampler (scaled by the robot's speed scaling, speed_scaling_input 1).
        link: the gateway link serving the action.
    """

    name = NAME
    type_name = TYPE

    def __init__(self, core: TrajectoryController, link: GatewayLink) -> None:
        super().__init__()
        self.core = core
        self._link = link
        self._goal: _Goal | None = None

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        p = cfg.tf_prefix
        joints = prefixed_joints(cfg.joints, p)
        command = tuple(f'{p}{PASSTHROUGH}/setpoint_{kind}_{i}' for i in range(len(joints))
                        for kind in ('positions', 'velocities', 'accelerations'))
        command += tuple(f'{p}{PASSTHROUGH}/{n}' for n in ('abort', 'transfer_state', 'time_from_start',
                                                            'trajectory_size'))
        return command, joint_interfaces(joints, 'position', 'velocity') + (f'{p}speed_scaling/speed_scaling_factor',)

    # ---- lifecycle (simulation loop, under the lock) --------------------------------------------------------------
    def on_activate(self) -> None:
        self.stop_reason = None
        self.core.hold(self.host.sim.state().q)

    def on_deactivate(self) -> None:
        self.core.hold(self.host.sim.state().q)
        goal, self._goal = self._goal, None
        if goal is not None:
            reason = DEACTIVATED if self.stop_reason is None else f'{DEACTIVATED} ({self.stop_reason})'
            self._link.send(Ended(goal.token, result_codes.INVALID_GOAL, reason))

    def refusal(self, topic: bool) -> str | None:
        """Under the lock: why this controller refuses a goal now, or None (it has no topic: `topic` is unused)."""
        refusal = self.robot_refusal()
        return refusal if refusal is not None or self.active else INACTIVE

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        goal = self._goal
        if goal is not None and self.core.trajectory is None and self._robot_at_end(goal):
            self._goal = None
            code, message = judge_end(state.q, state.qd, goal.final, goal.final_velocity, goal.tol, goal.elapsed,
                                      goal.duration)
            log = self.node.get_logger()
            if code == result_codes.SUCCESSFUL:
                log.info(message)
            else:
                log.error(f'Trajectory failed: {message}')
            self._link.send(Ended(goal.token, code, message))
        elif goal is not None:
            goal.elapsed += period * self.host.speed_scaling.factor
        sample, _ = self.core.update(state.t, period, state.q, state.qd)
        return sample, self.core.stop

    def halt(self, q: np.ndarray, reason: str) -> None:
        self.core.hold(q)
        goal, self._goal = self._goal, None
        if goal is not None:
            self.node.get_logger().info(f'Trajectory aborted by hardware, aborting action ({reason}).')
            self._link.send(Ended(goal.token, result_codes.SUCCESSFUL, reason, aborted=True))

    def _robot_at_end(self, goal: _Goal) -> bool:
        sp = self.host.sim.last_setpoint
        return sp is not None and bool(np.all(np.abs(sp.positions - goal.final) <= AT_REST)) and \
            bool(np.all(np.abs(sp.velocities) <= AT_REST))

    # ---- from the gateway (its receiving thread) -----------------------------------------------------------------
    def on_gateway(self, message: object) -> None:
        """A trajectory or cancel for this controller."""
        host = self.host
        if isinstance(message, Start):
            try:
                points = robot_points(map_to_config_order(message.command, self.core.joint_names,
                                                          host.sim.state().q))
            except TrajectoryError as exc:  # validated in the gateway: only a bug gets here
                self.node.get_logger().error(f'trajectory not started: {exc}')
                return
            tol: PassthroughTolerances = message.tolerances
            last = points.positions[-1]
            given_velocity = message.command.sizes[-1, 1] > 0
            final_velocity = points.velocities[-1] if given_velocity else None
            with host.lock:
                refusal = self.refusal(topic=False)  # admitted, but the state may have changed since
                if refusal is None and self._goal is not None:  # the gateway refuses a second goal: a race only
                    refusal = BUSY
                if refusal is None:
                    state = host.sim.state()
                    self.core.start(points, state.t, state.q, state.qd)
                    self._goal = _Goal(message.token, tol, last.copy(), final_velocity, points.duration)
                    self.node.get_logger().info(f'Accepted new trajectory with {len(points.times)} points.')
            if refusal is not None:
                self._link.send(Ended(message.token, result_codes.INVALID_GOAL, refusal))
        elif isinstance(message, Cancel):
            with host.lock:
                goal = self._goal
                ok = goal is not None and goal.token == message.token
                if ok:
                    self.node.get_logger().info('Cancelling active trajectory requested.')
                    self._goal = None
                    self.core.hold(host.sim.state().q)
            self._link.send(Canceled(message.token, ok))
