"""The robot's inputs and outputs as a UR control box and tool flange have them, without ROS.

Channels (ur_msgs numbering, as io_and_status_controller reports them):

* 18 digital inputs and 18 digital outputs: 0-7 standard, 8-15 configurable, 16-17 tool.
* 2 standard analog inputs and 2 standard analog outputs, each in a domain: current (4-20 mA) or voltage
  (0-10 V), as configured in the robot's installation.
* 2 tool analog inputs (ToolDataMsg ``analog_input2`` / ``analog_input3``), each in a range: current or voltage.
* the tool supply voltage: 0, 12 or 24 V.

Facts from the driver (ur_controllers' GPIOController and ur_client_library's RTDE writer, jazzy): an analog
output is commanded as a fraction of its span in [0, 1] (the URScript ``set_standard_analog_out`` convention)
and read back in amperes or volts; ``set_io`` keeps an output's domain, ``set_analog_output`` sets it; a
digital output is on for any non-zero state. Analog values here are in A (current) or V (voltage).

An :class:`IoBank` is immutable: a change makes a new bank (``with_*``), so that the simulation can replace
``Simulator.io`` under its lock while publishers read a consistent snapshot without it. The ``*_refusal``
functions validate a change and return None when it may be made, else a reason naming the field, the value
and the limit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

N_DIGITAL = 18  # digital inputs and outputs each: 0-7 standard, 8-15 configurable, 16-17 tool
N_ANALOG = 2  # standard analog inputs and outputs each
N_TOOL_ANALOG = 2  # tool analog inputs
CURRENT, VOLTAGE = 0, 1  # ur_msgs/Analog domains (equal to ToolDataMsg's ANALOG_INPUT_RANGE_*)
DOMAIN_NAMES = {CURRENT: 'CURRENT', VOLTAGE: 'VOLTAGE'}
# Signal span of each domain [A] or [V] (UR control box and tool: 4-20 mA, 0-10 V).
SPAN = {CURRENT: (0.004, 0.020), VOLTAGE: (0.0, 10.0)}
UNIT = {CURRENT: 'A', VOLTAGE: 'V'}
TOOL_VOLTAGES = (0, 12, 24)  # [V] the tool supply can be switched to


@dataclass(frozen=True)
class IoBank:
    """All IO channels at one instant.

    Attributes:
        digital_in, digital_out: (18,) levels.
        analog_in, analog_out: (2,) values [A or V, by domain].
        analog_in_domain, analog_out_domain: (2,) CURRENT or VOLTAGE.
        tool_analog_in: (2,) tool analog inputs [A or V, by range].
        tool_analog_in_range: (2,) CURRENT or VOLTAGE.
        tool_voltage: tool supply [V], one of 0, 12, 24.
    """

    digital_in: tuple[bool, ...] = (False,) * N_DIGITAL
    digital_out: tuple[bool, ...] = (False,) * N_DIGITAL
    analog_in: tuple[float, ...] = (0.0,) * N_ANALOG
    analog_in_domain: tuple[int, ...] = (VOLTAGE,) * N_ANALOG
    analog_out: tuple[float, ...] = (0.0,) * N_ANALOG
    analog_out_domain: tuple[int, ...] = (VOLTAGE,) * N_ANALOG
    tool_analog_in: tuple[float, ...] = (0.0,) * N_TOOL_ANALOG
    tool_analog_in_range: tuple[int, ...] = (VOLTAGE,) * N_TOOL_ANALOG
    tool_voltage: int = 0

    # ---- outputs (the driver's services) -------------------------------------------------------
    def with_digital_out(self, pin: int, state: float) -> IoBank:
        """Digital output `pin` on for any non-zero `state` (validate with :func:`digital_refusal`)."""
        return replace(self, digital_out=_set(self.digital_out, pin, state != 0.0))

    def with_analog_out(self, pin: int, fraction: float, domain: int | None = None) -> IoBank:
        """Analog output `pin` at `fraction` of its span, in `domain` (None keeps the configured one)."""
        domains = self.analog_out_domain if domain is None else _set(self.analog_out_domain, pin, domain)
        lo, hi = SPAN[domains[pin]]
        return replace(self, analog_out=_set(self.analog_out, pin, lo + fraction * (hi - lo)),
                       analog_out_domain=domains)

    def with_tool_voltage(self, volts: float) -> IoBank:
        return replace(self, tool_voltage=int(volts))

    # ---- inputs (the simulated world, e.g. a test or a sensor model) ------------------------------
    def with_digital_in(self, pin: int, state: float) -> IoBank:
        return replace(self, digital_in=_set(self.digital_in, pin, state != 0.0))

    def with_analog_in(self, pin: int, value: float, domain: int | None = None) -> IoBank:
        """Standard analog input `pin` (0-1) or tool analog input (`pin` 2-3) reads `value` [A or V]."""
        if pin < N_ANALOG:
            domains = self.analog_in_domain if domain is None else _set(self.analog_in_domain, pin, domain)
            return replace(self, analog_in=_set(self.analog_in, pin, value), analog_in_domain=domains)
        k = pin - N_ANALOG
        ranges = self.tool_analog_in_range if domain is None else _set(self.tool_analog_in_range, k, domain)
        return replace(self, tool_analog_in=_set(self.tool_analog_in, k, value), tool_analog_in_range=ranges)

    def analog_in_domain_of(self, pin: int) -> int:
        """Domain of standard analog input `pin` (0-1) or tool analog input (`pin` 2-3)."""
        return self.analog_in_domain[pin] if pin < N_ANALOG else self.tool_analog_in_range[pin - N_ANALOG]


def _set(values: tuple, i: int, value) -> tuple:
    return (*values[:i], value, *values[i + 1:])


# ---- validation ------------------------------------------------------------------------------------
def digital_refusal(pin: int, state: float, what: str = 'digital output') -> str | None:
    """None when `state` may be written to digital channel `pin` (0-17), else why not."""
    if not 0 <= pin < N_DIGITAL:
        return f'{what} pin = {pin} is outside 0..{N_DIGITAL - 1}'
    if not math.isfinite(state):
        return f'{what} {pin}: state = {state} is not a finite number (0 is off, anything else on)'
    return None


def domain_refusal(domain: int, what: str) -> str | None:
    if domain not in DOMAIN_NAMES:
        return f'{what}: domain = {domain} is neither {CURRENT} (CURRENT) nor {VOLTAGE} (VOLTAGE)'
    return None


def analog_out_refusal(pin: int, fraction: float, domain: int | None = None) -> str | None:
    """None when analog output `pin` (0-1) may be set to `fraction` of its span in [0, 1], else why not."""
    if not 0 <= pin < N_ANALOG:
        return f'analog output pin = {pin} is outside 0..{N_ANALOG - 1}'
    if domain is not None and (reason := domain_refusal(domain, f'analog output {pin}')) is not None:
        return reason
    if not (math.isfinite(fraction) and 0.0 <= fraction <= 1.0):
        return (f'analog output {pin}: state = {fraction} is outside [0, 1] '
                f'(the output is set as a fraction of its span: 4-20 mA or 0-10 V)')
    return None


def analog_in_refusal(bank: IoBank, pin: int, value: float, domain: int | None = None) -> str | None:
    """None when analog input `pin` (0-1 standard, 2-3 tool) may read `value` [A or V] in `domain`
    (None: the input's configured domain), else why not: the value must lie in the domain's span."""
    if not 0 <= pin < N_ANALOG + N_TOOL_ANALOG:
        return (f'analog input pin = {pin} is outside 0..{N_ANALOG + N_TOOL_ANALOG - 1} '
                f'(0-1 standard, 2-3 tool)')
    what = f'analog input {pin}'
    if domain is not None and (reason := domain_refusal(domain, what)) is not None:
        return reason
    d = bank.analog_in_domain_of(pin) if domain is None else domain
    lo, hi = SPAN[d]
    if not (math.isfinite(value) and lo <= value <= hi):
        return f'{what}: state = {value} {UNIT[d]} is outside [{lo}, {hi}] {UNIT[d]} ({DOMAIN_NAMES[d]} domain)'
    return None


def tool_voltage_refusal(volts: float) -> str | None:
    """None when the tool supply may be switched to `volts`, else why not."""
    if volts not in TOOL_VOLTAGES:
        return f'tool voltage: state = {volts} V is not one of {", ".join(map(str, TOOL_VOLTAGES))} V'
    return None
