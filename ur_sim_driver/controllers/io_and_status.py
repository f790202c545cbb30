"""io_and_status_controller (ur_controllers/GPIOController): the robot's IO, status and a few robot commands.

Every control cycle it publishes ``~/io_states`` (ur_msgs/IOStates: 18 digital in and out, 2 analog in and
out, no flags) and ``~/tool_data`` (ur_msgs/ToolDataMsg); ``~/robot_mode``, ``~/safety_mode`` and
``~/robot_program_running`` are transient local and published when they change, so that a late subscriber
gets the current value. The IO lives in ``Simulator.io`` (an immutable :class:`~ur_sim_driver.robot.io_bank.IoBank`
replaced under the simulation lock), where the simulated world (a dispenser model, ``/ur_sim/set_input``)
reads and writes it too.

Services, with upstream's semantics (ur_controllers/src/gpio_controller.cpp, jazzy):

* ``~/set_io`` (ur_msgs/SetIO): fun 1 digital output, pins 0-17, on for any non-zero state; fun 3 analog
  output, pins 0-1, state a fraction of the span in [0, 1], domain kept; fun 4 tool voltage 0, 12 or 24 V;
  fun 2 (flags) and anything else answer success false. The response has no message: the reason of a
  refusal is logged (as upstream logs it).
* ``~/set_analog_output`` (ur_msgs/SetAnalogOutput): pin 0-1, domain CURRENT or VOLTAGE, state in [0, 1].
* ``~/set_speed_slider`` (ur_msgs/SetSpeedSliderFraction): 0.01 .. 1.0, else success false; the slider
  multiplies the robot's speed scaling (``speed_scaling.py``).
* ``~/resend_robot_program``, ``~/hand_back_control`` (std_srvs/Trigger): the External Control program
  plays again (only in ``headless_mode``, as the driver sends its program only then) / ends (``robot_state.py``).
* ``~/set_payload`` (ur_msgs/SetPayload), ``~/zero_ftsensor`` (std_srvs/Trigger): validated here, then
  applied by ``Simulator.set_payload`` / ``Simulator.zero_ftsensor``.

Upstream's ``set_force_mode`` service of older releases is not offered (jazzy has force_mode_controller).
"""
from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import serialize_message
from std_msgs.msg import Bool
from std_srvs.srv import Trigger
from ur_dashboard_msgs.msg import RobotMode, SafetyMode
from ur_msgs.msg import Analog, Digital, IOStates, ToolDataMsg
from ur_msgs.srv import SetAnalogOutput, SetIO, SetPayload, SetSpeedSliderFraction

from ur_sim_driver.controllers.base import Component, Cycle, Host
from ur_sim_driver.controllers.cdr_template import listened, raw_publish
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.io_bank import (
    IoBank,
    analog_out_refusal,
    digital_refusal,
    tool_voltage_refusal,
)
from ur_sim_driver.robot.robot_state import POWER_OFF, RobotStatus
from ur_sim_driver.robot.speed_scaling import SLIDER_MAX, SLIDER_MIN

TOOL_TEMPERATURE = 32.0  # [deg C] the tool flange's temperature (constant: no thermal model)
TOOL_SUPPLY = 48.0  # [V] the tool's internal supply while the arm has power


def payload_refusal(ur_type: str, mass: float, cog: np.ndarray, inertia: np.ndarray,
                    transition_time: float) -> str | None:
    """None when the payload may be set, else why not.

    Args:
        ur_type: robot type (its rating limits the mass).
        mass: [kg], in [0, rating].
        cog: (3,) centre of gravity [m] in tool0.
        inertia: (6,) ixx, iyy, izz, ixy, ixz, iyz [kg m^2]; the principal terms must be >= 0.
        transition_time: [s] >= 0.
    """
    rating = load_ur_params(ur_type).payload  # UR's data sheet
    if not (math.isfinite(mass) and 0.0 <= mass <= rating):
        return f'mass = {mass} kg is outside [0, {rating}] kg (the rated payload of a {ur_type.upper()})'
    for axis, value in zip('xyz', cog):
        if not math.isfinite(value):
            return f'center_of_gravity.{axis} = {value} m is not a finite number'
    for name, value in zip(('ixx', 'iyy', 'izz', 'ixy', 'ixz', 'iyz'), inertia):
        if not math.isfinite(value):
            return f'{name} = {value} kg m^2 is not a finite number'
        if name in ('ixx', 'iyy', 'izz') and value < 0.0:
            return f'{name} = {value} kg m^2 is negative; a principal moment of inertia must be >= 0'
    if not (math.isfinite(transition_time) and transition_time >= 0.0):
        return f'transition_time = {transition_time} s is negative'
    return None


NOT_HEADLESS = 'Tried to send robot program directly while not in headless mode'


class IoAndStatusController(Component):
    """The driver's GPIOController over the simulated robot."""

    name = 'io_and_status_controller'
    type_name = 'ur_controllers/GPIOController'

    def on_configure(self, host: Host, node: Node) -> None:
        p = lambda x: host.cfg.prefixed(f'{self.name}/{x}')  # noqa: E731
        self._pub_io = node.create_publisher(IOStates, p('io_states'), 10)
        self._pub_tool = node.create_publisher(ToolDataMsg, p('tool_data'), 10)
        self._publish_io, self._publish_tool = raw_publish(self._pub_io), raw_publish(self._pub_tool)
        self._io_listened, self._tool_listened = listened(self._pub_io), listened(self._pub_tool)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._pub_robot_mode = node.create_publisher(RobotMode, p('robot_mode'), latched)
        self._pub_safety_mode = node.create_publisher(SafetyMode, p('safety_mode'), latched)
        self._pub_running = node.create_publisher(Bool, p('robot_program_running'), latched)
        node.create_service(SetIO, p('set_io'), self._on_set_io)
        node.create_service(SetAnalogOutput, p('set_analog_output'), self._on_set_analog_output)
        node.create_service(SetSpeedSliderFraction, p('set_speed_slider'), self._on_set_speed_slider)
        node.create_service(Trigger, p('resend_robot_program'), self._on_resend_robot_program)
        node.create_service(Trigger, p('hand_back_control'), self._on_hand_back_control)
        node.create_service(SetPayload, p('set_payload'), self._on_set_payload)
        node.create_service(Trigger, p('zero_ftsensor'), self._on_zero_ftsensor)
        self._io_msg = IOStates()
        self._tool_msg = ToolDataMsg()
        self._io_seen: IoBank | None = None
        self._status: RobotStatus | None = None
        self._key: tuple | None = None  # robot mode, safety mode, program state and program last published

    # ---- every cycle (simulation thread) -----------------------------------------------------------
    def update(self, cycle: Cycle) -> None:
        host = self.host
        io = host.sim.io  # one reference read: a consistent snapshot without the lock
        robot = host.robot
        key = (robot.robot_mode, robot.safety_mode, robot.program_state, robot.loaded_program)
        if io is self._io_seen and key == self._key:
            # Nothing changed since the last cycle (nearly always): the same bytes go out again.
            self._send()
            return
        self._key = key
        status = robot.status()
        last = self._status
        if io is not self._io_seen or last is None or status.robot_mode != last.robot_mode:
            self._fill(io, status)
            self._io_seen = io
            # Neither message has a stamp: between changes the same bytes go out every cycle. Serialized once
            # here, a publish costs about 3 us instead of about 58 us (40 nested messages converted each time).
            self._io_bytes = serialize_message(self._io_msg)
            self._tool_bytes = serialize_message(self._tool_msg)
        self._send()
        if last is None or status.robot_mode != last.robot_mode:
            self._pub_robot_mode.publish(RobotMode(mode=status.robot_mode))
        if last is None or status.safety_mode != last.safety_mode:
            self._pub_safety_mode.publish(SafetyMode(mode=status.safety_mode))
        if last is None or status.program_running != last.program_running:
            self._pub_running.publish(Bool(data=status.program_running))
        self._status = status

    def _send(self) -> None:
        """This cycle's io_states and tool_data, to whoever is subscribed (``cdr_template.listened``)."""
        if self._io_listened():
            self._publish_io(self._io_bytes)
        if self._tool_listened():
            self._publish_tool(self._tool_bytes)

    def _fill(self, io: IoBank, status: RobotStatus) -> None:
        m = self._io_msg
        m.digital_in_states = [Digital(pin=i, state=s) for i, s in enumerate(io.digital_in)]
        m.digital_out_states = [Digital(pin=i, state=s) for i, s in enumerate(io.digital_out)]
        m.analog_in_states = [Analog(pin=i, domain=d, state=v)
                              for i, (v, d) in enumerate(zip(io.analog_in, io.analog_in_domain))]
        m.analog_out_states = [Analog(pin=i, domain=d, state=v)
                               for i, (v, d) in enumerate(zip(io.analog_out, io.analog_out_domain))]
        t = self._tool_msg
        powered = status.robot_mode > POWER_OFF
        t.analog_input_range2, t.analog_input_range3 = io.tool_analog_in_range
        t.analog_input2, t.analog_input3 = io.tool_analog_in
        t.tool_voltage_48v = TOOL_SUPPLY if powered else 0.0
        t.tool_output_voltage = io.tool_voltage if powered else 0
        t.tool_current = 0.0  # no tool load is modelled
        t.tool_temperature = TOOL_TEMPERATURE
        t.tool_mode = ToolDataMsg.TOOL_RUNNING_MODE if powered else ToolDataMsg.TOOL_IDLE_MODE

    # ---- services (executor threads) -----------------------------------------------------------------
    def _change_io(self, reason: str | None, change: Callable[[IoBank], IoBank], done: str) -> bool:
        """Apply `change` to the IO bank under the lock unless `reason` refuses it; log either way."""
        log = self.node.get_logger()
        if reason is not None:
            log.error(f'refused: {reason}')
            return False
        with self.host.lock:
            self.host.sim.io = change(self.host.sim.io)
        log.info(done)
        return True

    def _on_set_io(self, req: SetIO.Request, res: SetIO.Response) -> SetIO.Response:
        fun, pin, state = int(req.fun), int(req.pin), float(req.state)
        if fun == SetIO.Request.FUN_SET_DIGITAL_OUT:
            res.success = self._change_io(digital_refusal(pin, state), lambda io: io.with_digital_out(pin, state),
                                          f'digital output {pin} set to {int(state != 0.0)}')
        elif fun == SetIO.Request.FUN_SET_ANALOG_OUT:
            res.success = self._change_io(analog_out_refusal(pin, state), lambda io: io.with_analog_out(pin, state),
                                          f'analog output {pin} set to {state:.4f} of its span')
        elif fun == SetIO.Request.FUN_SET_TOOL_VOLTAGE:
            res.success = self._change_io(tool_voltage_refusal(state), lambda io: io.with_tool_voltage(state),
                                          f'tool voltage set to {state:.0f} V')
        elif fun == SetIO.Request.FUN_SET_FLAG:
            res.success = self._change_io('fun = 2 (FUN_SET_FLAG): flags cannot be set (as with the driver)',
                                          lambda io: io, '')
        else:
            res.success = self._change_io(
                f'fun = {fun} is not 1 (FUN_SET_DIGITAL_OUT), 3 (FUN_SET_ANALOG_OUT) or 4 (FUN_SET_TOOL_VOLTAGE)',
                lambda io: io, '')
        return res

    def _on_set_analog_output(self, req: SetAnalogOutput.Request,
                              res: SetAnalogOutput.Response) -> SetAnalogOutput.Response:
        pin, domain, state = int(req.data.pin), int(req.data.domain), float(req.data.state)
        res.success = self._change_io(analog_out_refusal(pin, state, domain),
                                      lambda io: io.with_analog_out(pin, state, domain),
                                      f'analog output {pin} set to {state:.4f} of its span in domain {domain}')
        return res

    def _on_set_speed_slider(self, req: SetSpeedSliderFraction.Request,
                             res: SetSpeedSliderFraction.Response) -> SetSpeedSliderFraction.Response:
        f = float(req.speed_slider_fraction)
        log = self.node.get_logger()
        if not (SLIDER_MIN <= f <= SLIDER_MAX):
            log.error(f'refused: speed_slider_fraction = {f} is outside [{SLIDER_MIN}, {SLIDER_MAX}]')
            res.success = False
            return res
        with self.host.lock:
            self.host.speed_scaling.slider = f
        log.info(f'speed slider set to {f * 100.0:.2f} %')
        res.success = True
        return res

    def _robot_command(self, command: Callable[[], str | None], done: str,
                       res: Trigger.Response) -> Trigger.Response:
        with self.host.lock:
            reason = command()
        res.success = reason is None
        res.message = done if reason is None else reason
        if reason is None:
            self.node.get_logger().info(res.message)
        else:
            self.node.get_logger().error(f'refused: {res.message}')
        return res

    def _on_resend_robot_program(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        # The driver sends its program itself only in headless mode (UrDriver::sendRobotProgram); otherwise the
        # External Control program is started on the robot (play).
        resend = self.host.robot.resend_robot_program if self.host.cfg.headless_mode else (lambda: NOT_HEADLESS)
        return self._robot_command(resend, 'Successfully resent robot program', res)

    def _on_hand_back_control(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        return self._robot_command(self.host.robot.hand_back_control, 'Deactivated control', res)

    def _on_set_payload(self, req: SetPayload.Request, res: SetPayload.Response) -> SetPayload.Response:
        cog = np.array([req.center_of_gravity.x, req.center_of_gravity.y, req.center_of_gravity.z])
        inertia = np.array([req.ixx, req.iyy, req.izz, req.ixy, req.ixz, req.iyz])
        transition = req.transition_time.sec + req.transition_time.nanosec * 1e-9
        mass = float(req.mass)
        reason = payload_refusal(self.host.cfg.simulated_ur_type, mass, cog, inertia, transition)
        res.success = False
        if reason is not None:
            self.node.get_logger().error(f'refused: {reason}')
            return res
        try:
            with self.host.lock:
                self.host.sim.set_payload(mass, cog, inertia)
        except ConfigError as exc:  # what the physics cannot take (e.g. an inertia that is no rigid body's)
            self.node.get_logger().error(f'refused: {exc}')
            return res
        self.node.get_logger().info(f'payload set: {mass} kg at {cog.tolist()} m')
        res.success = True
        return res

    def _on_zero_ftsensor(self, req: Trigger.Request, res: Trigger.Response) -> Trigger.Response:
        with self.host.lock:
            self.host.sim.zero_ftsensor()
        res.success, res.message = True, 'Successfully zeroed the force torque sensor'
        return res
