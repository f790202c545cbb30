"""The `ur_sim` node: a MuJoCo-simulated UR arm behind the UR ROS 2 driver's interfaces.

Threads: the simulation loop runs in its own thread (``sim_loop.py``: paced to the wall clock, or as fast as
possible) and publishes every control cycle. The driver's controllers are components (``controllers/``), each its
own node, held by the controller manager (``controllers/controller_manager_node.py``), which switches them between two
cycles; the active joint controller (a trajectory or forward command controller) gives the robot its reference
every cycle. The trajectory controllers' action servers and joint_trajectory subscriptions run in a process of
their own (``gateway/gateway_process.py``, started here), so that receiving a large trajectory never holds up the
loop; a receiving thread hands its trajectories and cancels to their controller under one lock, and the
controllers send back outcomes and feedback. Every stamp is simulated time on the stamps' clock
(``conversions.RobotClock``: in real time counted from the system clock at start), which the node publishes on
/clock. The executable (executors, signals) is ``main.py``; a client in step with the loop, ``pace_gate.py``.
"""
from __future__ import annotations

import tempfile
import threading
import time
from pathlib import Path

from rclpy.node import Node
from rosgraph_msgs.msg import Clock

from ur_sim_driver.controllers import startup
from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.controllers.controller_manager_node import ControllerManagerNode
from ur_sim_driver.controllers.dispenser import SimulatedDispenser
from ur_sim_driver.controllers.force_mode import ForceModeController
from ur_sim_driver.controllers.force_torque_sensor_broadcaster import ForceTorqueSensorBroadcaster
from ur_sim_driver.controllers.forward_command import ForwardCommandController
from ur_sim_driver.controllers.freedrive_mode import FreedriveModeController
from ur_sim_driver.controllers.friction_model import FrictionModelController
from ur_sim_driver.controllers.gravity_update import GravityUpdateController
from ur_sim_driver.controllers.io_and_status import IoAndStatusController
from ur_sim_driver.controllers.joint_command import HoldPosition, JointCommandController, JointCommander
from ur_sim_driver.controllers.joint_state_broadcaster import JointStateBroadcaster
from ur_sim_driver.controllers.joint_trajectory import JointTrajectoryControllerComponent
from ur_sim_driver.controllers.part_scanner import PartScanners
from ur_sim_driver.controllers.passthrough_trajectory import PassthroughTrajectoryController
from ur_sim_driver.controllers.speed_scaling_state_broadcaster import SpeedScalingStateBroadcaster
from ur_sim_driver.controllers.tcp_pose_broadcaster import TcpPoseBroadcaster
from ur_sim_driver.controllers.tool_contact import ToolContactController
from ur_sim_driver.controllers.ur_configuration import UrConfigurationController
from ur_sim_driver.gateway.gateway_link import Admission, Admit, Dropped, GatewayConfig, GatewayLink, Received, Start
from ur_sim_driver.gateway.memory import use_mmap_for_large_blocks
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion.jtc import TrajectoryController
from ur_sim_driver.motion.tolerances import default_tolerances
from ur_sim_driver.physics.physics import ArmState
from ur_sim_driver.ports.dashboard_port import DashboardPort
from ur_sim_driver.ports.interpreter_port import InterpreterPort, has_interpreter_socket
from ur_sim_driver.ports.primary_port import REALTIME, SECONDARY, PrimaryPort
from ur_sim_driver.ports.rtde_fields import CycleValues
from ur_sim_driver.ports.rtde_port import RtdePort
from ur_sim_driver.ports.script_sockets import ScriptSockets
from ur_sim_driver.ports.tcp_port import PortError, close_all
from ur_sim_driver.robot.dashboard_server import DashboardServer
from ur_sim_driver.robot.direct_torque import STOPJ_DECELERATION
from ur_sim_driver.robot.encoders import reported_velocity
from ur_sim_driver.robot.motor_currents import current_as_torque, motor_currents
from ur_sim_driver.robot.robot_state import NORMAL, RUNNING, RobotState
from ur_sim_driver.robot.safety import ContactSafety, limit_cause, motion_limit_cause
from ur_sim_driver.robot.sim_config import PARAMETER_NAMES, SimConfig, sim_config_from_params, unknown_parameters
from ur_sim_driver.robot.simulator import BRAKE_CAPABILITY, Simulator
from ur_sim_driver.robot.speed_scaling import RobotSpeedScaling
from ur_sim_driver.ros.dashboard import DashboardClient
from ur_sim_driver.ros.pace_gate import PaceGate
from ur_sim_driver.ros.robot_state_helper import RobotStateHelper
from ur_sim_driver.ros.robot_state_publisher import RobotStatePublisher
from ur_sim_driver.ros.sim_io import SimulatedInputs
from ur_sim_driver.ros.sim_loop import SimLoop
from ur_sim_driver.ros.sim_wrench import AppliedWrenches
from ur_sim_driver.ros.trajectory_until import TrajectoryUntilNode
from ur_sim_driver.ros.urscript_interface import URScriptInterface
from ur_sim_driver.urscript.runner import ScriptRunner

UNSCALED_CONTROLLER = 'joint_trajectory_controller'


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
            {name: p.value for name, p in self.get_parameters_by_prefix('').items() if name != 'use_sim_time'})
        self._warn_unknown_parameters()
        self.sim = Simulator(self.cfg)
        use_mmap_for_large_blocks()  # long trajectories' arrays go back to the system when dropped
        # The controller's joints carry the tf_prefix, as in the driver's ur_controllers.yaml.
        self.joints = self.sim.joint_names
        self._defaults = default_tolerances(
            self.joints, trajectory=[c.trajectory for c in self.cfg.constraints],
            goal=[c.goal for c in self.cfg.constraints], stopped_velocity=self.cfg.stopped_velocity_tolerance,
            goal_time=self.cfg.goal_time)
        # The robot's own speed scaling, whichever controller commands it.
        self.scaling = RobotSpeedScaling(self.sim.params.v_max, self.sim.a_max)
        self._lock = threading.Lock()
        self._cycle = 0
        # Trajectories, cancels and dropped topic messages handled from the gateway, in order (read by tests and
        # scripts that step the simulation themselves: a command has reached its controller when this counts it).
        self.commands_received = 0
        self.robot = RobotState(powered_off=self.cfg.start_powered_off, programs=self.cfg.programs)
        self.contact_safety = ContactSafety(self.cfg.protective_stop_force,
                                            max(1, round(self.cfg.protective_stop_window * self.sim.control_rate)))
        self._refusal = self.robot.motion_refusal()

        p = self.cfg.prefixed
        ctrl = self.cfg.controller_name
        initial = startup.initial_joint_controller(self.cfg)  # checked before the gateway process starts
        startup.check_start(self.cfg)
        self._pub_clock = self.create_publisher(Clock, '/clock', 10)
        # Stamps: in real time they read as the system clock, as the driver's do (conversions.RobotClock).
        real_time = self.cfg.real_time_factor > 0.0 and not self.cfg.pace_topic
        self.clock = conv.RobotClock(time.time_ns() if real_time else 0)
        # In step with a client: the loop waits for the robot time it last handled.
        self.pace = PaceGate(self, self.cfg.pace_topic, self.clock, self.cfg.pace_lag) if self.cfg.pace_topic else None

        params = self.sim.params
        trajectory_names = (ctrl,) if ctrl == UNSCALED_CONTROLLER else (ctrl, UNSCALED_CONTROLLER)
        self._trajectory: dict[str, JointTrajectoryControllerComponent] = {}
        # Set once the node is set up: the gateway process answers clients from its start, and a goal sent
        # meanwhile waits for the controllers (it had found none, and the error ended the receiving thread).
        self._controllers_ready = threading.Event()
        self.gateway = GatewayLink(GatewayConfig(
            controllers=(*trajectory_names, PassthroughTrajectoryController.name),
            passthrough=(PassthroughTrajectoryController.name,), namespace=self.cfg.namespace, joints=self.joints,
            q_min=params.q_min, q_max=params.q_max, v_max=params.v_max, strict_limits=self.cfg.strict_limit_checks,
            allow_partial=self.cfg.allow_partial_joints_goal,
            allow_nonzero_end_velocity=self.cfg.allow_nonzero_velocity_at_trajectory_end,
            defaults=self._defaults, clock=self.clock), self._on_gateway)

        # The driver's controllers and nodes, one module each; the controller manager holds them.
        # The robot's file system for this run (the dashboard's flight reports and support files).
        self._robot_files = tempfile.TemporaryDirectory(prefix='ur_sim_robot_')
        files = Path(self._robot_files.name)
        logger = self.get_logger()
        scripts = ScriptRunner(self.sim, self.robot, lambda: self.scaling.factor,
                               lambda text: logger.info(f'textmsg: {text}'),
                               lambda: ScriptSockets(lambda: self.sim.time, logger.warning,
                                                     self.cfg.allow_remote_sockets),
                               lambda spec: self._force_mode.from_program(spec))
        self.host = Host(self.cfg, self.sim, self._lock, self.robot, self.scaling, self.context, files,
                         DashboardServer(self.robot, self.cfg.simulated_ur_type, self.cfg.software_version, files),
                         scripts, self.clock)
        feedback_every = round(self.sim.control_rate / self.cfg.action_monitor_rate)
        for name in trajectory_names:
            core = TrajectoryController(self.joints, self._defaults, self.sim.state().q, params.v_max,
                                        self.sim.a_max, self.cfg.initial_scaling_factor,
                                        scaling=self.scaling, scaled=name != UNSCALED_CONTROLLER)
            self._trajectory[name] = JointTrajectoryControllerComponent(name, core, self.gateway, feedback_every,
                                                                        initially_active=name == initial)
        # The robot's own interpolation for the passthrough controller: the JTC's sampler, scaled by the robot.
        self._passthrough = PassthroughTrajectoryController(
            TrajectoryController(self.joints, self._defaults, self.sim.state().q, params.v_max, self.sim.a_max,
                                 scaling=self.scaling, scaled=True), self.gateway)
        self._gateway_controllers = {**self._trajectory, self._passthrough.name: self._passthrough}
        self._tool_contact = ToolContactController()
        self._force_mode = ForceModeController()
        self.components: list[Component] = [
            JointStateBroadcaster(), SpeedScalingStateBroadcaster(), TcpPoseBroadcaster(),
            IoAndStatusController(), UrConfigurationController(), GravityUpdateController(), FrictionModelController(),
            *((DashboardClient(),) if self.cfg.launch_dashboard_client else ()), RobotStateHelper(),
            TrajectoryUntilNode(), URScriptInterface(), SimulatedInputs(),
            ForceTorqueSensorBroadcaster(), RobotStatePublisher(), SimulatedDispenser(), PartScanners(),
            *self._trajectory.values(), ForwardCommandController('position'), ForwardCommandController('velocity'),
            ForwardCommandController('effort'),
            self._passthrough, self._force_mode, FreedriveModeController(), self._tool_contact, AppliedWrenches()]
        warning = startup.set_start_states(self.cfg, initial, self.components)
        if warning is not None:
            self.get_logger().warning(warning)
        if self.cfg.hardware_components_initial_state == 'unconfigured':
            self.robot.stop()  # no driver to connect to: the External Control program does not run
        for component in self.components:
            component.configure(self.host)
            if component.initially_active:
                component.activate()
        self.controller_manager = ControllerManagerNode(self.host, [c for c in self.components if c.is_controller])
        self._commanders = [c for c in self.components if isinstance(c, JointCommandController)]
        self._holder = HoldPosition()
        self._last_read: tuple | None = None  # (state, tcp position, tcp orientation, wrench) the hardware last read
        self._commander: JointCommander | None = None
        self.controller_manager.program_state_changed(self._refusal)

        self._init_messages()
        cfg = self.cfg
        values = CycleValues(self.host)  # the output variables RTDE and the real-time interface stream, read once
        self.dashboard_port = self._open_port('dashboard server', 'dashboard_server.port', lambda: DashboardPort(
            cfg.dashboard_server_host, cfg.dashboard_server_port, self.host.dashboard, self._lock,
            self.get_logger().info))
        self.rtde_port = self._open_port('RTDE', 'rtde.port', lambda: RtdePort(
            cfg.rtde_host, cfg.rtde_port, self.host, self.sim.control_rate, self.get_logger().info, values))
        self.primary_ports = [port for port in (
            self._open_port('primary interface', 'primary.port', lambda: PrimaryPort(
                cfg.primary_host, cfg.primary_port, self.host, log=self.get_logger().info)),
            self._open_port('secondary interface', 'secondary.port', lambda: PrimaryPort(
                cfg.secondary_host, cfg.secondary_port, self.host, SECONDARY, log=self.get_logger().info)),
            self._open_port('real-time interface', 'realtime.port', lambda: PrimaryPort(
                cfg.realtime_host, cfg.realtime_port, self.host, REALTIME, log=self.get_logger().info,
                values=values)))
            if port is not None]
        # PolyScope 5.10+ on an e-Series only, as the robot
        self.interpreter_port = self._open_port('interpreter socket', 'interpreter.port', lambda: InterpreterPort(
            cfg.interpreter_host, cfg.interpreter_port, self.host.scripts, self._lock, cfg.software_version)) \
            if has_interpreter_socket(cfg.software_version) else None
        self.loop = SimLoop(self.step_once, self.sim, self.cfg, self.clock, self.pace, self._lock, self.context,
                            self.get_logger())
        self._controllers_ready.set()
        if start:
            self.loop.start()
        mode = 'as fast as possible' if self.cfg.real_time_factor == 0 else f'RTF {self.cfg.real_time_factor}'
        self.get_logger().info(
            f'{self.cfg.ur_type} simulated at {self.sim.control_rate:.0f} Hz control '
            f'({self.sim.physics.substeps} physics substeps), {mode}; action '
            f'{p(f"{ctrl}/follow_joint_trajectory")}')

    # ---- set-up ----------------------------------------------------------------------------------
    def _warn_unknown_parameters(self) -> None:
        for name in unknown_parameters(self.get_parameters_by_prefix('')):
            self.get_logger().warning(f"parameter '{name}' is not used by ur_sim; valid names: {PARAMETER_NAMES}")

    def nodes(self) -> list[Node]:
        """This node, the controller manager's and every component's: an executor spinning ur_sim must spin all."""
        return [self, self.controller_manager.node, *(c.node for c in self.components if c.node is not None)]

    @property
    def jtc(self) -> TrajectoryController:
        """The scaled trajectory controller's core (the driver's default controller)."""
        return self._trajectory[self.cfg.controller_name].core

    def _init_messages(self) -> None:
        # CDR bytes patched in place (cdr_template.py)
        self._clock_cdr = CdrTemplate(Clock(), stamps=('clock',), publisher=self._pub_clock)

    # ---- from the gateway process (its receiving thread) -------------------------------------------------------
    def _on_gateway(self, message: object) -> None:
        """A question, trajectory, cancel or dropped topic message for one of the trajectory controllers."""
        self._controllers_ready.wait()  # only a message sent while ur_sim starts waits (for its set-up)
        if isinstance(message, Dropped):
            self.commands_received += 1
            return
        controller = self._gateway_controllers.get(message.controller)
        if controller is None:  # only a bug gets here: the gateway serves exactly these controllers
            self.get_logger().error(f'gateway message for unknown controller {message.controller!r}')
            return
        with self._lock:
            # A robot state changed since the last cycle (a dashboard call) is seen now, as the driver's
            # controller_stopper would have seen it before this message arrived.
            self.robot.update(self.sim.time)
            self._controller_stopper()
            if isinstance(message, Admit):
                reason, now = controller.refusal(message.topic), self.sim.time
        if isinstance(message, Admit):
            self.gateway.send(Admission(message.request, reason, now))
            return
        controller.on_gateway(message)
        self.commands_received += 1
        if isinstance(message, Start) and message.token is not None:
            self.gateway.send(Received(message.token))  # the goal is with its controller (or already ended)

    # ---- the control cycle (the loop's thread, sim_loop.py, or a caller stepping it) -----------------------------
    def step_once(self) -> None:
        """One control cycle: pending controller switches, robot state, the active joint controller's reference,
        torques, physics step, safety, then the active components publish."""
        with self._lock:
            self.controller_manager.apply_pending()
            state = self.sim.state()
            # What the hardware reads and the controllers see: velocities as the robot's controller counts them
            # (encoders.py), efforts as the driver reads them (motor currents [A], or the torques less gravity
            # with use_currents_as_efforts false). The robot's own servo works on the simulated state.
            efforts = (motor_currents(self.sim, state) if self.cfg.use_currents_as_efforts
                       else current_as_torque(self.sim, state))
            reported = ArmState(state.t, state.q, reported_velocity(state.qd, self.sim.control_dt), efforts)
            self.robot.update(state.t)
            self._controller_stopper()
            hardware = self.controller_manager.hardware
            # A URScript program commands the arm while it plays; else the driver's commands reach the robot only
            # while the hardware component writes (is active).
            commander = self.host.scripts.commander()
            if commander is None:
                commander = next((c for c in self._commanders if c.active), self._holder) if hardware.writes \
                    else self._holder
            if commander is not self._commander:
                p = self.sim.params
                stopped = commander is self._holder and self._commander is not None
                if stopped and self.robot.motion_refusal() is None:
                    # No controller commands any more (a switch): the driver's program ends its servo, speed or
                    # torque thread with a stopj (hardware_interface.cpp write(): keepalive, MODE_IDLE), and the
                    # arm holds where it comes to rest.
                    self._holder.stop(reported, STOPJ_DECELERATION, p.q_min, p.q_max)
                elif stopped and self._commander.torques() is not None:
                    # Torque control stopped by the robot: it brakes as hard as it can and holds where it comes
                    # to rest (no position command to hold).
                    self._holder.stop(reported, BRAKE_CAPABILITY * p.a_max, p.q_min, p.q_max)
                else:
                    commander.take_over(reported)
                self._commander = commander
            sample, stop = commander.command(reported, self.sim.control_dt)
            tcp_position, tcp_orientation = self.sim.tcp_pose()
            wrench = self.sim.wrench()
            hold = self._force_mode.take_hold(sample, state)
            if hold is not None:  # force mode has ended: the robot holds where it left the reference
                commander.take_over(hold)
                sample, stop = commander.command(reported, self.sim.control_dt)
            if self._force_mode.spec is not None:
                sample, stop = self._force_mode.apply(sample, stop, tcp_position, self.sim.tcp_velocity()[:3],
                                                      tcp_orientation, wrench, self.sim.control_dt)
            torques = commander.torques()
            if getattr(commander, 'free', False):  # freedrive: the robot compensates gravity, the arm is free
                tau = self.sim.advance_free(state)
            elif torques is not None:  # torque control: the commanded torques on top of gravity compensation
                tau = self.sim.advance_torque(state, torques, getattr(commander, 'friction_scales', None))
            else:
                tau = self.sim.advance(state, sample, stop)
            contacts = self.sim.physics.contacts()  # measured over this cycle's physics steps
            if self._tool_contact.watching:
                halted = self._tool_contact.detect(contacts, self.sim.time)
                if halted is not None:  # the robot cancels the motion: the next cycle brakes
                    commander.halt(self.sim.state().q, halted)
            cause = self._safety_check(sample, contacts, torques is not None)
            if cause is not None:
                # Seen in this cycle's physics step: the arm is halted from the next cycle on.
                self.robot.protective_stop(self.sim.time, cause)
                self._controller_stopper()
            robot_factor = self.scaling.factor
            self.host.scripts.after_cycle()
            self.host.check_waiters()
        if hardware.reads or self._last_read is None:
            self._last_read = (reported, tcp_position, tcp_orientation, wrench)
        # Not read (the driver is disconnected): the state interfaces keep the values last read.
        measured, tcp_position, tcp_orientation, wrench = self._last_read
        cycle = Cycle(self._cycle, state.t, self.clock.parts(state.t), measured, sample, tau, robot_factor,
                      tcp_position, tcp_orientation, wrench)
        for component in self.components:
            if component.active:
                component.update(cycle)
        self._publish(cycle)
        if self.rtde_port is not None:
            self.rtde_port.tick()
        for port in self.primary_ports:
            port.tick()
        if cause is not None:
            self.get_logger().error(f'PROTECTIVE_STOP: {cause}')
        self._cycle += 1

    def _safety_check(self, sample, contacts, torque_control: bool) -> str | None:
        """Under the lock, after the physics step: the cause of a protective stop, or None. The checks are armed
        while the robot can move (RUNNING, NORMAL); see ``safety.py``. Under torque control no reference bounds the
        motion: the measured stopping distances are checked against the position limits
        (``safety.motion_limit_cause``)."""
        armed = self.robot.robot_mode == RUNNING and self.robot.safety_mode == NORMAL
        cause = self.contact_safety.update(contacts, armed)
        if cause is None and armed:
            p = self.sim.params
            if torque_control:
                after = self.sim.state()
                cause = motion_limit_cause(after.q, after.qd, p.q_min, p.q_max, self.sim.a_max, self.joints)
            else:
                cause = limit_cause(self.sim.physics.positions(), sample.positions, p.q_min, p.q_max, self.joints)
        return cause

    def _controller_stopper(self) -> None:
        """Under the lock: when the robot can no longer move, the controllers that command it are deactivated (their
        goals end and the robot holds), and activated again when it can, as the driver's controller_stopper does."""
        refusal = self.robot.motion_refusal()
        if refusal == self._refusal:
            return
        self._refusal = refusal
        self.controller_manager.program_state_changed(refusal)

    def _open_port(self, what: str, parameter: str, open_it):
        """One of the robot's TCP ports (`open_it()`); None (and a warning) when its address cannot be used: the ROS
        side runs on without it, as a second simulator on one machine must."""
        try:
            port = open_it()
        except PortError as exc:
            self.get_logger().warning(f'{exc}; set {parameter} (0: any free port) to serve it')
            return None
        self.get_logger().info('{} listening on {}:{}'.format(what, *port.address))
        return port

    def _publish(self, cycle: Cycle) -> None:
        if self._clock_cdr.listened():
            self._clock_cdr.publish((), cycle.stamp_parts)

    def shutdown(self) -> None:
        """Stop the simulation loop and the controller's interface process, and wait for both."""
        self.loop.stop()
        close_all([port for port in (self.dashboard_port, self.rtde_port, *self.primary_ports, self.interpreter_port)
                   if port is not None])
        self.gateway.close()

    def destroy_node(self) -> None:
        for component in self.components:
            component.destroy()
        self.controller_manager.destroy()
        super().destroy_node()
        self._robot_files.cleanup()
