"""Simulation only: set the robot's digital and analog inputs from a test or a script.

A real robot's inputs are driven by the wiring (sensors, a PLC); the driver has no service for them. In the
simulation this component stands in for the world outside the control box. Its services live under
``/ur_sim/`` (within ur_sim's namespace) so that no user mistakes them for the driver's:

* ``/ur_sim/set_input`` (ur_msgs/srv/SetIO, reused with these meanings of ``fun``):
  ``fun`` 1 sets digital input ``pin`` (0-17: 0-7 standard, 8-15 configurable, 16-17 tool), off for state 0,
  on otherwise; ``fun`` 3 sets analog input ``pin`` (0-1 standard, 2-3 the tool's ``analog_input2`` /
  ``analog_input3``) to ``state`` in amperes or volts, in the input's configured domain and within its span
  (4-20 mA, 0-10 V). Any other ``fun`` answers success false.
* ``/ur_sim/set_analog_input`` (ur_msgs/srv/SetAnalogOutput, reused): analog input ``data.pin`` (0-3 as
  above) in domain ``data.domain`` (CURRENT 0, VOLTAGE 1) reads ``data.state`` [A or V]; this also changes
  the input's domain, as reconfiguring the installation would.

The responses carry only ``success``; the reason of a refusal is logged. The change shows in the next
``/io_and_status_controller/io_states`` (``tool_data`` for the tool's analog inputs).
"""
from __future__ import annotations

from rclpy.node import Node
from ur_msgs.srv import SetAnalogOutput, SetIO

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.robot.io_bank import analog_in_refusal, digital_refusal

FUN_SET_DIGITAL_IN = SetIO.Request.FUN_SET_DIGITAL_OUT  # 1, reused for inputs
FUN_SET_ANALOG_IN = SetIO.Request.FUN_SET_ANALOG_OUT  # 3, reused for inputs


class SimulatedInputs(Component):
    """``/ur_sim/set_input`` and ``/ur_sim/set_analog_input``: simulation-only writers of the inputs."""

    name = 'ur_sim_inputs'
    type_name = 'ur_sim/SimulatedInputs'
    is_controller = False

    def on_configure(self, host: Host, node: Node) -> None:
        node.create_service(SetIO, host.cfg.prefixed('ur_sim/set_input'), self._on_set_input)
        node.create_service(SetAnalogOutput, host.cfg.prefixed('ur_sim/set_analog_input'),
                            self._on_set_analog_input)

    def _apply(self, pin: int, value: float, domain: int | None, digital: bool) -> bool:
        log = self.node.get_logger()
        with self.host.lock:  # validated under the lock: an analog value is checked against the current domain
            io = self.host.sim.io
            reason = (digital_refusal(pin, value, 'digital input') if digital
                      else analog_in_refusal(io, pin, value, domain))
            if reason is None:
                self.host.sim.io = (io.with_digital_in(pin, value) if digital
                                    else io.with_analog_in(pin, value, domain))
        if reason is not None:
            log.error(f'refused: {reason}')
            return False
        log.info(f'{"digital" if digital else "analog"} input {pin} set to {value}')
        return True

    def _on_set_input(self, req: SetIO.Request, res: SetIO.Response) -> SetIO.Response:
        fun, pin, state = int(req.fun), int(req.pin), float(req.state)
        if fun in (FUN_SET_DIGITAL_IN, FUN_SET_ANALOG_IN):
            res.success = self._apply(pin, state, None, digital=fun == FUN_SET_DIGITAL_IN)
        else:
            self.node.get_logger().error(f'refused: fun = {fun} is not {FUN_SET_DIGITAL_IN} (digital input) or '
                                         f'{FUN_SET_ANALOG_IN} (analog input)')
            res.success = False
        return res

    def _on_set_analog_input(self, req: SetAnalogOutput.Request,
                             res: SetAnalogOutput.Response) -> SetAnalogOutput.Response:
        res.success = self._apply(int(req.data.pin), float(req.data.state), int(req.data.domain), digital=False)
        return res
