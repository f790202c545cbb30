"""scaled_joint_trajectory_controller and joint_trajectory_controller: the JTC as a controller of ur_sim.

The per-cycle logic is ``jtc.py`` (trajectory, tolerances, goal supervision); this module gives it the controller's
lifecycle and its interfaces. ``~/follow_joint_trajectory`` and ``~/joint_trajectory`` are served by the gateway process
(``gateway_process.py``, one ``TrajectoryGateway`` per controller on its node) so that receiving a large goal never
stalls the simulation loop; this side executes what the gateway hands over and serves, on the controller's own node in
this process, ``~/controller_state`` (every cycle while active), ``~/query_state``
(control_msgs/srv/QueryTrajectoryState) and ``~/speed_scaling_input`` (control_msgs/msg/SpeedScalingFactor).

The scaled controller advances trajectory time by the robot's speed scaling (the hardware's
``speed_scaling/speed_scaling_factor``); joint_trajectory_controller by its own factor (``~/speed_scaling_input``,
1.0 unless told), whatever the robot makes of it, so a motion the robot must slow down for ends in a path
tolerance violation instead of being stretched. Both take ``~/speed_scaling_input`` as ros2_controllers' JTC does
for a position-only controller (jazzy 4.39 and later: QoS system default, transient local; a factor below 0 is
ignored with a warning); in the scaled one (a16a268's ``ScaledJointTrajectoryController``) it changes only the
``speed_scaling_factor`` its ``controller_state`` reports: the motion follows the hardware's factor, kept in a
member of the scaled controller's own, while the inherited ``publish_state`` reports the base class's.

Deactivated (by switch_controller or by the controller_stopper), the controller holds the measured position
and ends its goal aborted (INVALID_GOAL); an inactive controller refuses goals and messages with upstream's
words (the gateway learns each switch before switch_controller answers).
"""
from __future__ import annotations

import numpy as np
from control_msgs.msg import JointTrajectoryControllerState, SpeedScalingFactor
from control_msgs.srv import QueryTrajectoryState
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.qos import qos_profile_system_default as _SYSTEM

from ur_sim_driver.controllers.base import Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.controllers.controller_state import ARRAYS as STATE_ARRAYS
from ur_sim_driver.controllers.controller_state import FIELDS as STATE_FIELDS
from ur_sim_driver.controllers.controller_state import pack_state
from ur_sim_driver.controllers.joint_command import JointCommandController
from ur_sim_driver.controllers.ur_hardware import joint_interfaces, prefixed_joints
from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway.gateway_link import Cancel, Canceled, Ended, Feedback, GatewayLink, Start
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.jtc import INACTIVE_GOAL, INACTIVE_TOPIC, Outcome, TrajectoryController
from ur_sim_driver.motion.trajectory import TrajectorySample
from ur_sim_driver.motion.validation import map_to_config_order
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.robot.sim_config import SimConfig

# ros2_controllers' ~/speed_scaling_input: rclcpp::SystemDefaultsQoS().transient_local()
SPEED_SCALING_QOS = QoSProfile(history=_SYSTEM.history, depth=_SYSTEM.depth, reliability=_SYSTEM.reliability,
                               durability=DurabilityPolicy.TRANSIENT_LOCAL)
SCALED_TYPE = 'ur_controllers/ScaledJointTrajectoryController'
UNSCALED_TYPE = 'joint_trajectory_controller/JointTrajectoryController'
DEACTIVATED = 'Current goal cancelled during deactivate transition.'  # upstream's words; the goal is aborted here
QUERY_INACTIVE = "Can't sample trajectory. Controller is not active."
QUERY_NO_TRAJECTORY = 'Currently there is no valid trajectory instance.'


class JointTrajectoryControllerComponent(JointCommandController):
    """One trajectory controller.

    Args:
        name: the controller's name.
        core: its per-cycle logic (sharing the robot's speed scaling with the other controllers).
        link: the gateway link serving its action and topic.
        feedback_every: publish action feedback every this many cycles.
        initially_active: active after start (the driver starts the scaled one).
    """

    def __init__(self, name: str, core: TrajectoryController, link: GatewayLink, feedback_every: int,
                 initially_active: bool = False) -> None:
        super().__init__()
        self.name = name
        self.core = core
        self.scaled = core.scaled
        self.type_name = SCALED_TYPE if core.scaled else UNSCALED_TYPE
        self.initially_active = initially_active
        self._link = link
        self._feedback_every = max(1, feedback_every)
        self._token = None
        self.speed_scaling_received = 0  # speed_scaling_input messages handled
        self._desired: TrajectorySample | None = None  # this cycle's sample in trajectory time (under the lock)
        self._output: np.ndarray | None = None  # this cycle's position command, while controller_state is listened
        self._times = (0.0, 0.0)  # this cycle's reference and feedback time_from_start [s]

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        joints = prefixed_joints(cfg.joints, cfg.tf_prefix)
        state = joint_interfaces(joints, 'position', 'velocity')
        if self.scaled:
            state += (f'{cfg.tf_prefix}speed_scaling/speed_scaling_factor',)
        return joint_interfaces(joints, 'position'), state

    def on_configure(self, host: Host, node: Node) -> None:
        p = host.cfg.prefixed
        self._pub_state = node.create_publisher(JointTrajectoryControllerState, p(f'{self.name}/controller_state'),
                                                10)
        node.create_service(QueryTrajectoryState, p(f'{self.name}/query_state'), self._on_query,
                            callback_group=MutuallyExclusiveCallbackGroup())
        # Upstream: rclcpp::SystemDefaultsQoS().transient_local(); a volatile publisher does not match it.
        node.create_subscription(SpeedScalingFactor, p(f'{self.name}/speed_scaling_input'), self._on_speed_scaling,
                                 SPEED_SCALING_QOS,
                                 callback_group=MutuallyExclusiveCallbackGroup())
        # controller_state goes out as CDR bytes patched in place (cdr_template.py), with the arrays the
        # controller fills (controller_state.py): reference (q, qd, qdd), feedback and error (q, qd), output (q).
        zeros = [0.0] * len(self.core.joint_names)
        state = JointTrajectoryControllerState(joint_names=list(self.core.joint_names))
        for point, fields in STATE_FIELDS:
            for field in fields:
                setattr(getattr(state, point), field, zeros)
        self._state_cdr = CdrTemplate(state, stamps=('header.stamp', 'reference.time_from_start',
                                                     'feedback.time_from_start'), floats=(
            *(f'{point}.{field}' for point, fields in STATE_FIELDS for field in fields), 'speed_scaling_factor'),
            publisher=self._pub_state)
        self._state_values = np.empty(STATE_ARRAYS * len(self.core.joint_names) + 1)  # reused: publish copies it

    # ---- lifecycle (simulation loop, under the lock) --------------------------------------------------------------
    def on_activate(self) -> None:
        self.stop_reason = None
        self.core.hold(self.host.sim.state().q)  # upstream holds the current position on activation

    def on_deactivate(self) -> None:
        token = self.core.active_token
        self.core.hold(self.host.sim.state().q)
        if token is not None:
            # Upstream's words whatever the cause (on_deactivate); why (the controller_stopper's robot state) goes
            # to the log.
            detail = '' if self.stop_reason is None else f'the controller was deactivated: {self.stop_reason}'
            self._finish(Outcome(token, result_codes.INVALID_GOAL, DEACTIVATED, detail))
        self._token = None

    def refusal(self, topic: bool) -> str | None:
        """Under the lock: why this controller refuses a goal (or a topic message) now, or None; the robot's state
        first (the controller_stopper keeps the controller inactive while the robot cannot move)."""
        refusal = self.robot_refusal()
        if refusal is None and not self.active:
            refusal = INACTIVE_TOPIC if topic else INACTIVE_GOAL
        return refusal

    def command(self, state: ArmState, period: float) -> tuple[TrajectorySample, np.ndarray | None]:
        sample, outcome = self.core.update(state.t, period, state.q, state.qd)
        if outcome is not None:
            self._finish(outcome)
        self._token = self.core.active_token
        # controller_state's reference and output, read under the lock (a new trajectory may start outside it);
        # the output costs a second sample, taken only while someone subscribes.
        self._desired = self.core.desired
        self._times = self.core.time_from_start
        self._output = self.core.command_positions(period) if self._state_cdr.listened() else None
        return sample, self.core.stop

    def halt(self, q: np.ndarray, reason: str) -> None:
        token = self.core.active_token
        self.core.hold(q)
        self._token = None
        if token is not None:
            # Upstream's JTC is not told: the robot stops following, and the goal ends on its tolerances. ur_sim
            # ends it at once with the code a path tolerance would give, naming the cause.
            self._finish(Outcome(token, result_codes.PATH_TOLERANCE_VIOLATED, reason))

    # ---- every cycle while active (simulation loop, outside the lock) ---------------------------------------------
    def update(self, cycle: Cycle) -> None:
        state = cycle.state
        # The controller's own factor (in the scaled one too, as upstream's publish_state reports it; the robot's
        # is the speed_scaling_state_broadcaster's).
        factor = self.core.speed_scaling
        desired, output, (t_reference, t_feedback) = self._desired, self._output, self._times
        if output is not None and desired is not None and self._state_cdr.listened():
            stamps = cycle.stamp_parts + conv.duration_parts(t_reference) + conv.duration_parts(t_feedback)
            self._state_cdr.publish(pack_state(desired.positions, desired.velocities, desired.accelerations, state.q,
                                               state.qd, output, factor, self._state_values), stamps)
        token = self._token
        if token is not None and desired is not None and cycle.index % self._feedback_every == 0:
            # Upstream's feedback: desired in trajectory time, the error of the positions only (as controller_state).
            self._link.send(Feedback(token, state.t, (desired.positions, desired.velocities, desired.accelerations),
                                     (state.q, state.qd), (desired.positions - state.q, np.zeros_like(state.qd)),
                                     t_reference, t_feedback))

    # ---- from the gateway (its receiving thread) -----------------------------------------------------------------
    def on_gateway(self, message: object) -> None:
        """A trajectory or cancel for this controller."""
        host = self.host
        if isinstance(message, Start):
            try:
                # Mapping a long trajectory is done outside the lock the loop needs every cycle.
                points = map_to_config_order(message.command, self.core.joint_names, self._hold_reference())
            except TrajectoryError as exc:  # validated in the gateway: only a bug gets here
                self.node.get_logger().error(f'trajectory not started: {exc}')
                return
            preempted = None
            with host.lock:
                refusal = self.refusal(topic=message.token is None)  # admitted, but the state may have changed since
                if refusal is None:
                    state = host.sim.state()
                    preempted = self.core.start(points, state.t, state.q, state.qd, token=message.token,
                                                tolerances=message.tolerances)
                    self._token = self.core.active_token
            if refusal is not None:  # a topic message, or a goal accepted while the state changed
                if message.token is not None:
                    self._finish(Outcome(message.token, result_codes.INVALID_GOAL, refusal))
                else:
                    self.node.get_logger().warning(f'Dropped JointTrajectory message: {refusal}')
                return
            if preempted is not None:
                self._finish(preempted)
        elif isinstance(message, Cancel):
            with host.lock:
                ok = self.core.cancel(message.token, host.sim.state().q)
                self._token = self.core.active_token
            self._link.send(Canceled(message.token, ok))

    # ---- ROS callbacks (executor threads) -------------------------------------------------------------------------
    def _on_speed_scaling(self, msg: SpeedScalingFactor) -> None:
        """Upstream's set_scaling_factor: any factor >= 0 (above 1 speeds up), applied from the next cycle."""
        try:
            f = msg.factor
            if not f >= 0.0:  # upstream tests `scaling_factor < 0`; NaN is refused here as well
                self.node.get_logger().warning('Scaling factor has to be greater or equal to 0.0 - Ignoring input!')
                return
            if f != self.core.speed_scaling:
                self.node.get_logger().get_child('speed_scaling').info(f'New scaling factor will be {f:f}')
            with self.host.lock:
                self.core.speed_scaling = float(f)
        finally:
            # Counted once handled (applied or ignored): a script that steps the simulation itself waits for it.
            self.speed_scaling_received += 1

    def _on_query(self, request: QueryTrajectoryState.Request,
                  response: QueryTrajectoryState.Response) -> QueryTrajectoryState.Response:
        t = self.host.clock.sim_time(request.time)
        with self.host.lock:
            active, trajectory = self.active, self.core.trajectory
            sample = trajectory.sample(t) if active and trajectory is not None else None
        if sample is None:
            response.success = False
            response.message = QUERY_INACTIVE if not active else QUERY_NO_TRAJECTORY
            self.node.get_logger().error(response.message)
            return response
        response.success = True
        response.name = list(self.core.joint_names)
        response.position = conv.float_array(sample.positions)
        response.velocity = conv.float_array(sample.velocities)
        response.acceleration = conv.float_array(sample.accelerations)
        return response

    # ---- helpers -------------------------------------------------------------------------------------------------
    def _hold_reference(self) -> np.ndarray:
        # Joints a partial goal leaves out keep their current command (upstream), else the measured position.
        sample = self.core.last_sample
        return sample.positions.copy() if sample is not None else self.host.sim.state().q

    def _finish(self, outcome: Outcome) -> None:
        log = self.node.get_logger() if self.node is not None else None
        if log is not None and outcome.detail:
            log.error(outcome.detail)  # upstream prints the joint and its error (tolerances.hpp, show_errors)
        if outcome.token is not None:
            self._link.send(Ended(outcome.token, outcome.code, outcome.message))
        elif log is not None:
            log.error(outcome.message)  # a topic trajectory held on its tolerances: no goal to end
