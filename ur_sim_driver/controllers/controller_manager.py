"""ros2_control's controller manager, reduced to what ur_sim needs, without ROS.

It knows the loaded controllers (name, type, the command and state interfaces each needs), their lifecycle states
(unconfigured, inactive, active) and the hardware component, and decides what a ``switch_controller`` request does.
Rules, order of the checks and wording are those of ros2_control jazzy 4.46 (``controller_manager.cpp``:
``switch_controller_cb``, ``check_for_interfaces_availability_to_activate``, ``evaluate_switch_result``):

1. strictness 0 is taken as BEST_EFFORT (a warning); AUTO and FORCE_AUTO resolve controller chains upstream, and
   ur_sim has no chainable controllers, so they act as BEST_EFFORT;
2. unknown names, the deactivate list first: STRICT aborts, BEST_EFFORT drops them and fails only when none of the
   list's names exist;
3. activating a controller that is unconfigured or already active (not being restarted), deactivating one that is
   not active: STRICT aborts, BEST_EFFORT drops it; nothing left is a success;
4. interface availability, whatever the strictness: each command interface must be available, not claimed by a
   controller that stays active, and not claimed by two activations; each state interface must be available;
5. the hardware's ``prepare_command_mode_switch`` (the resource manager's refusal for an inactive component, then
   the UR hardware's mode table, ``ur_hardware.py``);
6. the switch: deactivations, then activations; a controller whose activation fails stays inactive (with STRICT
   every activation of that request is undone) and the request fails, naming it.

The lifecycle services (load, configure, cleanup, unload) are :mod:`controller_lifecycle`'s.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

from ur_sim_driver.controllers.hardware_component import HardwareComponent

BEST_EFFORT, STRICT, AUTO, FORCE_AUTO = 1, 2, 3, 4
STRICTNESS_NAMES = {BEST_EFFORT: 'BEST_EFFORT', STRICT: 'STRICT', AUTO: 'AUTO', FORCE_AUTO: 'FORCE_AUTO'}
UNCONFIGURED, INACTIVE, ACTIVE = 'unconfigured', 'inactive', 'active'
ABORT_STRICT = 'Aborting, no controller is switched! (::STRICT switch)'
ABORT_STRICT_UNKNOWN = "Aborting, no controller is switched! ('STRICT' switch)"
NOTHING_TO_DO = 'After checking the controllers, no controllers need to be activated or deactivated.'
SWITCHED = 'Successfully switched controllers!'
SWITCH_FAILED = 'Failed switching controllers.... '
HARDWARE_REJECTED = 'Could not switch controllers since prepare command mode switch was rejected.'
_SEE_ABOVE = ('Check above warnings for more details. Check the state of the controllers and their required '
              'interfaces using `ros2 control list_controllers -v` CLI to get more information.')

# Checks a switch against the hardware: (start, stop, running command interfaces) -> None or why not.
ModeCheck = Callable[[tuple[str, ...], tuple[str, ...], tuple[str, ...]], 'str | None']


@dataclass(frozen=True)
class ControllerSpec:
    """One loaded controller as the manager knows it.

    Attributes:
        name: the controller's name (its node's name).
        type_name: its plugin type, e.g. 'joint_trajectory_controller/JointTrajectoryController'.
        command_interfaces: command interfaces it claims while active (with the tf_prefix).
        state_interfaces: state interfaces it reads.
        unavailable: why its activation fails on this robot (its on_activate returns ERROR), or None.
        stops_with_program: the driver's controller_stopper deactivates it while the robot cannot move (every
            controller outside its "consistent" list of broadcasters and status controllers).
    """

    name: str
    type_name: str
    command_interfaces: tuple[str, ...] = ()
    state_interfaces: tuple[str, ...] = ()
    unavailable: str | None = None
    stops_with_program: bool = False


@dataclass(frozen=True)
class LogLine:
    """A line the manager logs: `level` is 'info', 'warn' or 'error'."""

    level: str
    text: str


@dataclass(frozen=True)
class SwitchPlan:
    """What a switch request comes to.

    Attributes:
        ok: the answer of switch_controller.
        message: the answer's message.
        deactivate, activate: the controllers to switch, in order (both empty when nothing is done).
        log: what the manager logs about the request, in order.
    """

    ok: bool
    message: str
    deactivate: tuple[str, ...]
    activate: tuple[str, ...]
    log: tuple[LogLine, ...]


def _refused(log: list[LogLine], action: str, name: str, why: str, strict: bool) -> bool:
    """Log that `name` cannot be (de)activated (`action`) and why; True when the request aborts (STRICT)."""
    log += [LogLine('warn', why), LogLine('warn', f"Could not {action} controller with name '{name}'. {_SEE_ABOVE}")]
    if strict:
        log.append(LogLine('error', ABORT_STRICT))
    return strict


class ControllerManager:
    """The loaded controllers, their states and the switch rules.

    Args:
        specs: the loaded controllers, in load order (list_controllers reports them in this order); all configured.
        active: names of the controllers active at start.
        mode_check: the hardware's check of a switch (see ``ur_hardware.prepare_command_mode_switch``);
            None accepts every switch.
        hardware: the hardware component all interfaces belong to; None: always available.

    Raises:
        ValueError: a duplicate name, an unknown initially active name, or initially active controllers that
            claim one command interface twice.
    """

    def __init__(self, specs: Iterable[ControllerSpec], active: Iterable[str] = (),
                 mode_check: ModeCheck | None = None, hardware: HardwareComponent | None = None) -> None:
        self.specs: dict[str, ControllerSpec] = {}
        self.states: dict[str, str] = {}
        for spec in specs:
            if spec.name in self.specs:
                raise ValueError(f"controller '{spec.name}' is loaded twice")
            self.specs[spec.name] = spec
            self.states[spec.name] = INACTIVE
        self.hardware = hardware
        self._mode_check = mode_check
        for name in active:
            if name not in self.specs:
                raise ValueError(f"initially active controller '{name}' is not loaded; loaded: {', '.join(self.specs)}")
            taken = self.claimed_interfaces()
            clash = [i for i in self.specs[name].command_interfaces if i in taken]
            if clash:
                raise ValueError(f"initially active controller '{name}' claims '{clash[0]}', already claimed by "
                                 f"'{taken[clash[0]]}'")
            self.states[name] = ACTIVE

    # ---- queries ---------------------------------------------------------------------------------------------
    def is_active(self, name: str) -> bool:
        return self.states.get(name) == ACTIVE

    def state(self, name: str) -> str:
        """'unconfigured', 'inactive' or 'active'."""
        return self.states[name]

    def claimed(self, name: str) -> tuple[str, ...]:
        """The command interfaces `name` holds now (none unless active)."""
        return self.specs[name].command_interfaces if self.is_active(name) else ()

    def claimed_interfaces(self) -> dict[str, str]:
        """Every claimed command interface -> the controller holding it."""
        return {i: n for n in self.specs if self.is_active(n) for i in self.specs[n].command_interfaces}

    def active_names(self) -> tuple[str, ...]:
        return tuple(n for n in self.specs if self.is_active(n))

    def interfaces_available(self) -> bool:
        """The hardware's interfaces are available (its component is configured)."""
        return self.hardware is None or self.hardware.available

    def is_claimed(self, interface: str) -> bool:
        """As the resource manager answers: an unavailable interface is never claimed."""
        return self.interfaces_available() and interface in self.claimed_interfaces()

    # ---- switching ---------------------------------------------------------------------------------------------
    def plan(self, activate: Iterable[str], deactivate: Iterable[str], strictness: int) -> SwitchPlan:
        """Decide a switch_controller request without changing anything (see the module docstring)."""
        log: list[LogLine] = []

        def fail(message: str) -> SwitchPlan:
            return SwitchPlan(False, message, (), (), tuple(log))

        if strictness == 0:
            log.append(LogLine('warn', 'Controller Manager: to switch controllers you need to specify a strictness '
                                       f'level of STRICT ({STRICT}) or BEST_EFFORT ({BEST_EFFORT}). Defaulting to '
                                       'BEST_EFFORT'))
            strictness = BEST_EFFORT
        if strictness not in STRICTNESS_NAMES:
            text = (f'strictness = {strictness} is not a valid strictness; valid: '
                    + ', '.join(f'{v} ({k})' for k, v in STRICTNESS_NAMES.items()))
            log.append(LogLine('error', text))
            return fail(text)
        strict = strictness == STRICT
        lists: dict[str, list[str]] = {'deactivate': [], 'activate': []}
        message = ''
        for action, names in (('deactivate', list(deactivate)), ('activate', list(activate))):
            for name in names:
                if name in self.specs:
                    if name not in lists[action]:
                        lists[action].append(name)
                    continue
                text = f"Could not {action} controller with name '{name}' because no controller with this name exists"
                log.append(LogLine('warn', text))
                message += text + '\n'
                if strict:
                    log.append(LogLine('error', ABORT_STRICT_UNKNOWN))
                    return fail(text)
            if names and not lists[action]:  # none of the list's names exist
                return fail(message)
        act, deact = lists['activate'], lists['deactivate']
        for name in list(act):
            if self.states[name] == UNCONFIGURED:
                text = (f"Controller with name '{name}' is in 'unconfigured' state. The controller needs to be "
                        "configured to be in 'inactive' state before it can be checked and activated.")
            elif self.is_active(name) and name not in deact:
                text = f"Controller with name '{name}' is already active."
            else:
                continue
            if _refused(log, 'activate', name, text, strict):
                return fail(text)
            act.remove(name)
        for name in list(deact):
            if not self.is_active(name):
                text = f"Controller with name '{name}' can not be deactivated since it is not active."
                if _refused(log, 'deactivate', name, text, strict):
                    return fail(text)
                deact.remove(name)
        if not act and not deact:
            log.append(LogLine('info', NOTHING_TO_DO))
            return SwitchPlan(True, NOTHING_TO_DO, (), (), tuple(log))
        reason = self._availability(act, deact)
        if reason is not None:
            log.append(LogLine('warn', reason))
            return fail(reason)
        start = tuple(i for n in act for i in self.specs[n].command_interfaces)
        stop = tuple(i for n in deact for i in self.specs[n].command_interfaces)
        if start or stop:
            refusal = self.hardware.rejects_start(start) if self.hardware is not None else None
            if refusal is not None:
                log.append(LogLine('warn', refusal))
            elif self._mode_check is not None:
                refusal = self._mode_check(start, stop, tuple(self.claimed_interfaces()))
                if refusal is not None:
                    log.append(LogLine('error', refusal))
            if refusal is not None:
                log.append(LogLine('error', HARDWARE_REJECTED))
                return fail(HARDWARE_REJECTED)
        return self._outcome(tuple(deact), tuple(act), strict, log)

    def _availability(self, act: list[str], deact: list[str]) -> str | None:
        """``check_for_interfaces_availability_to_activate``: why an activation cannot have its interfaces."""
        released = {i for n in deact for i in self.specs[n].command_interfaces}
        available = self.interfaces_available()
        claimed = self.claimed_interfaces() if available else {}
        wanted: set[str] = set()
        for name in act:
            if name in deact:  # a restart keeps its own interfaces
                continue
            spec = self.specs[name]
            for i in spec.command_interfaces:
                why = ('is not available' if not available else
                       'is currently claimed by another controller' if i in claimed and i not in released else
                       'will be used by another controller that is being activated' if i in wanted else None)
                if why is not None:
                    return f"Unable to activate controller '{name}' since the command interface '{i}' {why}."
                wanted.add(i)
            if spec.state_interfaces and not available:
                return (f"Unable to activate controller '{name}' since the state interface "
                        f"'{spec.state_interfaces[0]}' is not available.")
        return None

    def _outcome(self, deact: tuple[str, ...], act: tuple[str, ...], strict: bool, log: list[LogLine]) -> SwitchPlan:
        """The switch as done: activations that fail leave their controllers inactive (``evaluate_switch_result``)."""
        failed = [n for n in act if self.specs[n].unavailable]
        for name in failed:
            log.append(LogLine('error', f"Could not activate controller '{name}': {self.specs[name].unavailable}"))
        if failed:
            done = () if strict else tuple(n for n in act if n not in failed)
            text = SWITCH_FAILED + '\nUnable to activate controllers: [ ' + ''.join(f'{n} ' for n in failed) + ' ]'
            log.append(LogLine('error', text))
            return SwitchPlan(False, text, deact, done, tuple(log))
        message = SWITCHED
        if not strict:
            if deact:
                message += f'\nDeactivated controllers: [ {" ".join(deact)} ]'
            if act:
                message += f'\nActivated controllers: [ {" ".join(act)} ]'
        log.append(LogLine('info', SWITCHED))
        return SwitchPlan(True, message, deact, act, tuple(log))

    def apply(self, plan: SwitchPlan) -> None:
        """Record a planned switch as done (the caller runs the controllers' deactivate, then activate hooks).

        Raises:
            ValueError: the plan no longer fits the states (another switch came between plan and apply).
        """
        restarts = set(plan.deactivate) & set(plan.activate)
        bad = ([n for n in plan.deactivate if not self.is_active(n)]
               + [n for n in plan.activate if n not in restarts and self.states.get(n) != INACTIVE])
        if bad:
            raise ValueError(f"stale switch plan: '{bad[0]}' changed state since it was planned")
        for name in plan.deactivate:
            self.states[name] = INACTIVE
        for name in plan.activate:
            self.states[name] = ACTIVE

    # ---- controller_stopper ----------------------------------------------------------------------------------------
    def stoppable_active(self) -> tuple[str, ...]:
        """The active controllers the driver's controller_stopper deactivates while the robot cannot move."""
        return tuple(n for n in self.active_names() if self.specs[n].stops_with_program)
