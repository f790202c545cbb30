"""The `ur_sim` node: a MuJoCo-simulated UR arm behind the UR ROS 2 driver's interfaces.

Threads: the simulation loop runs in its own thread (paced to the wall clock, or as fast as possible) and
publishes every control cycle. The trajectory controller's action server and joint_trajectory subscription
run in a process of their own (``trajectory_gateway.py``, started here), so that receiving a large
trajectory never holds up the loop; a receiving thread hands its trajectories and cancels to the loop under
one lock, and the loop sends back outcomes and feedback. speed_scaling_input is served here. All times on the
interfaces are simulated time, which the node publishes on /clock.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time

import numpy as np
import rclpy
from control_msgs.msg import JointTrajectoryControllerState, SpeedScalingFactor
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock

from ur_sim_driver import conversions as conv
from ur_sim_driver import result_codes
from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.dispenser import SimulatedDispenser
from ur_sim_driver.controllers.force_torque_sensor_broadcaster import ForceTorqueSensorBroadcaster
from ur_sim_driver.controllers.io_and_status import IoAndStatusController
from ur_sim_driver.controllers.joint_state_broadcaster import JointStateBroadcaster
from ur_sim_driver.controllers.speed_scaling_state_broadcaster import SpeedScalingStateBroadcaster
from ur_sim_driver.controllers.tcp_pose_broadcaster import TcpPoseBroadcaster
from ur_sim_driver.controllers.ur_configuration import UrConfigurationController
from ur_sim_driver.dashboard import DashboardClient
from ur_sim_driver.errors import TrajectoryError, UrSimError
from ur_sim_driver.gateway_link import Cancel, Canceled, Ended, Feedback, Gate, GatewayConfig, GatewayLink, Start
from ur_sim_driver.jtc import Outcome, TrajectoryController
from ur_sim_driver.memory import use_mmap_for_large_blocks
from ur_sim_driver.robot_state import PROTECTIVE_STOP, RobotState
from ur_sim_driver.robot_state_publisher import RobotStatePublisher
from ur_sim_driver.safety import contact_cause, limit_cause
from ur_sim_driver.sim_config import SimConfig, sim_config_from_params
from ur_sim_driver.sim_io import SimulatedInputs
from ur_sim_driver.simulator import Simulator
from ur_sim_driver.tolerances import default_tolerances
from ur_sim_driver.validation import map_to_config_order

GIL_SWITCH_INTERVAL = 2e-4  # [s]
VIEWER_FRAME_PERIOD = 1.0 / 30.0  # [s] of wall time
_CATCH_UP_LIMIT = 0.1  # [s] of wall time the real-time loop may fall behind before it stops catching up


class UrSimNode(Node):
    """Simulated UR arm with the UR driver's topics and FollowJointTrajectory action.

    Args:
        context: rclpy context (the global one when None).
        parameter_overrides: parameters as if given with --ros-args -p (tests use this).
        start: start the simulation loop thread immediately.
    """

    def __init__(self, *, context=None, parameter_overrides=None, start: bool = True) -> None:
        super().__init__('ur_sim', context=context, parameter_overrides=parameter_overrides or [],
                         allow_undeclared_parameters=True,
                         automatically_declare_parameters_from_overrides=True)
        self.cfg: SimConfig = sim_config_from_params(
            {name: p.value for name, p in self._parameters.items() if name != 'use_sim_time'})
        self._warn_unknown_parameters()
        self.sim = Simulator(self.cfg)
        use_mmap_for_large_blocks()  # long trajectories' arrays go back to the system when dropped
        # The controller's joints carry the tf_prefix, as in the driver's ur_controllers.yaml.
        self.joints = self.sim.joint_names
        self._defaults = default_tolerances(
            self.joints, trajectory=[c.trajectory for c in self.cfg.constraints],
            goal=[c.goal for c in self.cfg.constraints], stopped_velocity=self.cfg.stopped_velocity_tolerance,
            goal_time=self.cfg.goal_time)
        self.jtc = TrajectoryController(self.joints, self._defaults, self.sim.state().q,
                                        self.sim.params.v_max, self.sim.a_max,
                                        self.cfg.speed_scaling_initial_factor)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._feedback_every = max(1, round(self.sim.control_rate / self.cfg.action_monitor_rate))
        self._cycle = 0
        self.robot = RobotState(powered_off=self.cfg.start_powered_off, programs=self.cfg.programs)
        self._refusal = self.robot.motion_refusal()

        p = self.cfg.prefixed
        ctrl = self.cfg.controller_name
        self._pub_state = self.create_publisher(JointTrajectoryControllerState, p(f'{ctrl}/controller_state'), 10)
        self._pub_clock = self.create_publisher(Clock, '/clock', 10)

        self.create_subscription(SpeedScalingFactor, p(f'{ctrl}/speed_scaling_input'), self._on_speed_scaling,
                                 10, callback_group=MutuallyExclusiveCallbackGroup())
        params = self.sim.params
        self.gateway = GatewayLink(GatewayConfig(
            node_name=ctrl, namespace=self.cfg.namespace, joints=self.joints, q_min=params.q_min,
            q_max=params.q_max, v_max=params.v_max, strict_limits=self.cfg.strict_limit_checks,
            allow_partial=self.cfg.allow_partial_joints_goal,
            allow_nonzero_end_velocity=self.cfg.allow_nonzero_velocity_at_trajectory_end,
            defaults=self._defaults), self._on_gateway)
        if self._refusal is not None:
            self.gateway.send(Gate(self._refusal))

        # The driver's controllers and nodes besides the trajectory controller, one module each.
        self.host = Host(self.cfg, self.sim, self._lock, self.robot, self.jtc.scaling, self.context)
        self.components: list[Component] = [
            JointStateBroadcaster(), SpeedScalingStateBroadcaster(), TcpPoseBroadcaster(),
            IoAndStatusController(), UrConfigurationController(), DashboardClient(), SimulatedInputs(),
            ForceTorqueSensorBroadcaster(), RobotStatePublisher(), SimulatedDispenser()]
        for component in self.components:
            component.configure(self.host)
            component.activate()

        self._init_messages()
        self._thread = threading.Thread(target=self._run, name='ur_sim_loop', daemon=True)
        if start:
            self._thread.start()
        mode = 'as fast as possible' if self.cfg.real_time_factor == 0 else f'RTF {self.cfg.real_time_factor}'
        self.get_logger().info(
            f'{self.cfg.ur_type} simulated at {self.sim.control_rate:.0f} Hz control '
            f'({self.sim.physics.substeps} physics substeps), {mode}; action '
            f'{p(f"{ctrl}/follow_joint_trajectory")}')

    # ---- set-up ----------------------------------------------------------------------------------
    def _warn_unknown_parameters(self) -> None:
        known = set(SimConfig.__dataclass_fields__) | {'use_sim_time', 'start_type_description_service'}
        for name in self._parameters:
            if name.split('.')[0] not in known and not name.startswith('constraints.'):
                self.get_logger().warning(f"parameter '{name}' is not used by ur_sim; valid names: "
                                          f"{', '.join(sorted(known - {'constraints'}))}, constraints.*")

    def nodes(self) -> list[Node]:
        """This node and every component's: an executor spinning ur_sim must spin all of them."""
        return [self, *(c.node for c in self.components if c.node is not None)]

    def _init_messages(self) -> None:
        joints = list(self.sim.joint_names)
        self._state_msg = JointTrajectoryControllerState(joint_names=joints)
        self._clock_msg = Clock()

    # ---- ROS callbacks (executor threads) ----------------------------------------------------------
    def _on_gateway(self, message: object) -> None:
        """A trajectory or cancel from the controller's interface process (receiving thread)."""
        if isinstance(message, Start):
            try:
                # Mapping a long trajectory is done outside the lock the loop needs every cycle.
                points = map_to_config_order(message.command, self.joints, self._hold_reference())
            except TrajectoryError as exc:  # validated in the gateway: only a bug gets here
                self.get_logger().error(f'trajectory not started: {exc}')
                return
            with self._lock:
                refusal = self.robot.motion_refusal()
                if refusal is None:
                    state = self.sim.state()
                    preempted = self.jtc.start(points, state.t, state.q, state.qd, token=message.token,
                                               tolerances=message.tolerances)
            if refusal is not None:  # a topic message, or a goal accepted while the state changed
                reason = f'the controller is not running: {refusal}'
                if message.token is not None:
                    self._finish(Outcome(message.token, result_codes.INVALID_GOAL, reason))
                else:
                    self.get_logger().error(f'Dropped JointTrajectory message: {reason}')
                return
            if preempted is not None:
                self._finish(preempted)
        elif isinstance(message, Cancel):
            with self._lock:
                ok = self.jtc.cancel(message.token, self.sim.state().q)
            self.gateway.send(Canceled(message.token, ok))

    def _on_speed_scaling(self, msg: SpeedScalingFactor) -> None:
        f = msg.factor
        if not (0.0 <= f <= 1.0):
            self.get_logger().error(f'Ignored speed_scaling_input: factor = {f} is outside [0.0, 1.0]; '
                                    f'keeping {self.jtc.speed_scaling}')
            return
        with self._lock:
            self.jtc.speed_scaling = float(f)

    def _hold_reference(self) -> np.ndarray:
        # Joints a partial goal leaves out keep their current command (upstream), else the measured position.
        sample = self.jtc.last_sample
        return sample.positions.copy() if sample is not None else self.sim.state().q

    def _finish(self, outcome: Outcome) -> None:
        if outcome.token is not None:
            self.gateway.send(Ended(outcome.token, outcome.code, outcome.message))

    # ---- simulation loop (own thread) ------------------------------------------------------------
    def _open_viewer(self):
        """MuJoCo's passive viewer where a display exists (`viewer: true`), else None with a warning."""
        if not self.cfg.viewer:
            return None
        if not (os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY')):
            self.get_logger().warning('viewer: true but no display (DISPLAY is unset); running without a viewer')
            return None
        try:
            import mujoco.viewer
            return mujoco.viewer.launch_passive(self.sim.physics.model, self.sim.physics.data)
        except Exception as exc:  # a broken GL setup must not stop the simulation
            self.get_logger().warning(f'viewer could not be opened ({exc!r}); running without a viewer')
            return None

    def _run(self) -> None:
        viewer = self._open_viewer()
        next_frame = 0.0
        dt = self.sim.control_dt
        rtf = self.cfg.real_time_factor
        wall_period = dt / rtf if rtf > 0 else 0.0
        next_wall = time.perf_counter()
        try:
            while not self._stop.is_set():
                self.step_once()
                if viewer is not None and time.perf_counter() >= next_frame:
                    with self._lock:
                        viewer.sync()
                    next_frame = time.perf_counter() + VIEWER_FRAME_PERIOD
                if wall_period > 0.0:
                    next_wall += wall_period
                    delay = next_wall - time.perf_counter()
                    if delay > 0.0:
                        time.sleep(delay)
                    elif delay < -_CATCH_UP_LIMIT:
                        next_wall = time.perf_counter()
                elif self._cycle % 8 == 0:
                    time.sleep(0)  # let executor threads take the GIL in fast mode
        except Exception as exc:
            if self._stop.is_set() or not self.context.ok():
                return  # shutting down: publishers may already be gone
            self.get_logger().fatal(f'simulation loop stopped: {exc!r}')
            raise
        finally:
            if viewer is not None:
                viewer.close()

    def step_once(self) -> None:
        """One control cycle: robot state, JTC update, torques, physics step, safety, then the components publish."""
        with self._lock:
            state = self.sim.state()
            self.robot.update(state.t)
            ended = [self._controller_stopper(state.q)]
            sample, outcome = self.jtc.update(state.t, self.sim.control_dt, state.q, state.qd)
            tcp_position, tcp_orientation = self.sim.tcp_pose()
            wrench = self.sim.wrench()
            tau = self.sim.advance(state, sample, self.jtc.stop)
            ended.append(outcome)
            cause = self._safety_check(sample)
            if cause is not None:
                # Seen in this cycle's physics step: the arm is halted from the next cycle on.
                self.robot.protective_stop(self.sim.time, cause)
                ended.append(self._controller_stopper(self.sim.state().q))
            token = self.jtc.active_token
            feedback_due = token is not None and self._cycle % self._feedback_every == 0
            robot_factor, total_factor = self.jtc.scaling.factor, self.jtc.scaling.total
        self.gateway.set_sim_time(self.sim.time)
        cycle = Cycle(self._cycle, state.t, conv.sec_to_time(state.t), state, sample, tau, robot_factor,
                      total_factor, tcp_position, tcp_orientation, wrench)
        for component in self.components:
            if component.active:
                component.update(cycle)
        self._publish(cycle)
        if feedback_due:
            self._publish_feedback(token, state, sample)
        for e in ended:
            if e is not None:
                self._finish(e)
        if cause is not None:
            self.get_logger().error(f'PROTECTIVE_STOP: {cause}')
        self._cycle += 1

    def _safety_check(self, sample) -> str | None:
        """Under the lock, after the physics step: the cause of a protective stop, or None."""
        if self.robot.safety_mode == PROTECTIVE_STOP:
            return None
        p = self.sim.params
        cause = contact_cause(self.sim.physics.contacts(), self.cfg.protective_stop_force)
        if cause is None:
            cause = limit_cause(self.sim.physics.positions(), sample.positions, p.q_min, p.q_max, self.joints)
        return cause

    def _controller_stopper(self, q: np.ndarray) -> Outcome | None:
        """Under the lock: when the robot can no longer move, hold `q` and end the active goal, as the driver's
        controller_stopper deactivates the controllers; tell the gateway of every change."""
        refusal = self.robot.motion_refusal()
        if refusal == self._refusal:
            return None
        self._refusal = refusal
        self.gateway.send(Gate(refusal))
        if refusal is None:
            return None
        token = self.jtc.active_token
        self.jtc.hold(q)
        if token is None:
            return None
        return Outcome(token, result_codes.INVALID_GOAL, f'the controller was deactivated: {refusal}')

    def _publish(self, cycle: Cycle) -> None:
        state, sample = cycle.state, cycle.reference
        st = self._state_msg
        st.header.stamp = cycle.stamp
        conv.fill_point(st.reference, sample.positions, sample.velocities, sample.accelerations)
        conv.fill_point(st.feedback, state.q, state.qd)
        conv.fill_point(st.error, sample.positions - state.q, sample.velocities - state.qd)
        conv.fill_point(st.output, sample.positions, sample.velocities, effort=cycle.effort)
        # The controller reports the factor it advances trajectory time by; the broadcaster the robot's own.
        st.speed_scaling_factor = cycle.total_factor
        self._pub_state.publish(st)
        self._clock_msg.clock = cycle.stamp
        self._pub_clock.publish(self._clock_msg)

    def _publish_feedback(self, token, state, sample) -> None:
        self.gateway.send(Feedback(token, state.t, (sample.positions, sample.velocities, sample.accelerations),
                                   (state.q, state.qd), (sample.positions - state.q, sample.velocities - state.qd)))

    def shutdown(self) -> None:
        """Stop the simulation loop and the controller's interface process, and wait for both."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)
        self.gateway.close()

    def destroy_node(self) -> None:
        for component in self.components:
            component.destroy()
        super().destroy_node()


def main(argv: list[str] | None = None) -> int:
    """Entry point of `ur_sim` (and `ros2 run ur_sim_driver ur_sim`). Exits 0 on SIGINT/SIGTERM, 2 on bad parameters."""
    # The simulation thread gives up the GIL in every MuJoCo and rcl call; with the default 5 ms switch
    # interval each hand-back can stall it behind an executor thread, which caps the loop far below 500 Hz.
    sys.setswitchinterval(GIL_SWITCH_INTERVAL)
    # Our own signal handling: stop the simulation thread first, then shut the context down, so that no
    # publish races the context's destruction.
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    node = None
    executor = MultiThreadedExecutor(num_threads=4)
    code = 0
    try:
        node = UrSimNode()
        for n in node.nodes():
            executor.add_node(n)
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except UrSimError as exc:
        print(f'ur_sim: {exc}', file=sys.stderr)
        code = 2
    finally:
        if node is not None:
            node.shutdown()
        executor.shutdown(timeout_sec=2.0)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == '__main__':
    sys.exit(main())
