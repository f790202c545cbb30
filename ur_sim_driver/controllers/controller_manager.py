"""ros2_control's controller manager, reduced to what ur_sim needs, without ROS.

It knows the loaded controllers (name, type, the command and state interfaces each needs) and which are
active, and decides what a ``switch_controller`` request does. The rules and log wording are those of
ros2_control jazzy's ``ControllerManager::switch_controller`` (facts read from controller_manager.cpp):

* strictness 0 is taken as BEST_EFFORT, with a warning; AUTO and FORCE_AUTO resolve controller chains upstream;
  ur_sim has no chainable controllers, so they act as BEST_EFFORT here;
* an unknown name: a warning; STRICT aborts the whole request, BEST_EFFORT drops the name;
* activating a controller that is not inactive, or deactivating one that is not active: warnings; STRICT aborts,
  BEST_EFFORT drops it (there is no restart: a controller in both lists while active cannot be activated);
* an activation that would claim a command interface another controller keeps (or one activated in the same
  request) is a resource conflict; STRICT aborts, BEST_EFFORT drops that activation;
* nothing left to do: "Empty activate and deactivate list, not requesting switch", which succeeds;
* the hardware (``ur_hardware.py``) then checks the robot modes; its refusal fails the request whatever the
  strictness;
* a switch deactivates first, then activates, between two control cycles.

Besides, a controller may be unavailable on this robot (:attr:`ControllerSpec.unavailable`, e.g. tool contact on
a CB3): activating one is refused like an impossible activation, naming why.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass

BEST_EFFORT, STRICT, AUTO, FORCE_AUTO = 1, 2, 3, 4
STRICTNESS_NAMES = {BEST_EFFORT: 'BEST_EFFORT', STRICT: 'STRICT', AUTO: 'AUTO', FORCE_AUTO: 'FORCE_AUTO'}
ACTIVE, INACTIVE = 'active', 'inactive'
ABORT_STRICT = "Aborting, no controller is switched! ('STRICT' switch)"
EMPTY_SWITCH = 'Empty activate and deactivate list, not requesting switch'
SWITCHED = 'Successfully switched controllers'
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
        unavailable: why ur_sim cannot activate it, or None.
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
        deactivate, activate: the controllers to switch, in order (both empty when nothing is done).
        log: what the manager logs about the request, in order.
    """

    ok: bool
    deactivate: tuple[str, ...]
    activate: tuple[str, ...]
    log: tuple[LogLine, ...]

    @property
    def message(self) -> str:
        """The response's message: the warnings and errors about the request, in order, or its success."""
        lines = [line.text for line in self.log if line.level != 'info']
        if lines:
            return ' '.join(lines)
        return SWITCHED if self.ok and (self.activate or self.deactivate) else EMPTY_SWITCH


def _fail(log: list[LogLine]) -> SwitchPlan:
    return SwitchPlan(False, (), (), tuple(log))


class ControllerManager:
    """The loaded controllers, their states and the switch rules.

    Args:
        specs: the loaded controllers, in load order (list_controllers reports them in this order).
        active: names of the controllers active at start.
        mode_check: the hardware's check of a switch (see ``ur_hardware.prepare_command_mode_switch``);
            None accepts every switch.

    Raises:
        ValueError: a duplicate name, an unknown initially active name, or initially active controllers that
            claim one command interface twice.
    """

    def __init__(self, specs: Iterable[ControllerSpec], active: Iterable[str] = (),
                 mode_check: ModeCheck | None = None) -> None:
        self.specs: dict[str, ControllerSpec] = {}
        for spec in specs:
            if spec.name in self.specs:
                raise ValueError(f"controller '{spec.name}' is loaded twice")
            self.specs[spec.name] = spec
        self._active: set[str] = set()
        self._mode_check = mode_check
        for name in active:
            if name not in self.specs:
                raise ValueError(f"initially active controller '{name}' is not loaded; loaded: {', '.join(self.specs)}")
            taken = self.claimed_interfaces()
            clash = [i for i in self.specs[name].command_interfaces if i in taken]
            if clash:
                raise ValueError(f"initially active controller '{name}' claims '{clash[0]}', already claimed by "
                                 f"'{taken[clash[0]]}'")
            self._active.add(name)

    # ---- queries ---------------------------------------------------------------------------------------------
    def is_active(self, name: str) -> bool:
        return name in self._active

    def state(self, name: str) -> str:
        """'active' or 'inactive' (every loaded controller is configured)."""
        return ACTIVE if name in self._active else INACTIVE

    def claimed(self, name: str) -> tuple[str, ...]:
        """The command interfaces `name` holds now (none while inactive)."""
        return self.specs[name].command_interfaces if name in self._active else ()

    def claimed_interfaces(self) -> dict[str, str]:
        """Every claimed command interface -> the controller holding it."""
        return {i: n for n in self.specs if n in self._active for i in self.specs[n].command_interfaces}

    def active_names(self) -> tuple[str, ...]:
        return tuple(n for n in self.specs if n in self._active)

    # ---- switching ---------------------------------------------------------------------------------------------
    def plan(self, activate: Iterable[str], deactivate: Iterable[str], strictness: int) -> SwitchPlan:
        """Decide a switch_controller request without changing anything (see the module docstring)."""
        log: list[LogLine] = []
        if strictness == 0:
            log.append(LogLine('warn', 'Controller Manager: to switch controllers you need to specify a strictness '
                                       f'level of STRICT ({STRICT}) or BEST_EFFORT ({BEST_EFFORT}). Defaulting to '
                                       'BEST_EFFORT'))
            strictness = BEST_EFFORT
        if strictness not in STRICTNESS_NAMES:
            log.append(LogLine('error', f'strictness = {strictness} is not a valid strictness; valid: '
                                        + ', '.join(f'{v} ({k})' for k, v in STRICTNESS_NAMES.items())))
            return _fail(log)
        strict = strictness == STRICT
        lists: dict[str, list[str]] = {'deactivate': [], 'activate': []}
        for action, names in (('deactivate', deactivate), ('activate', activate)):
            for name in names:
                if name not in self.specs:
                    log.append(LogLine('warn', f"Could not '{action}' controller with name '{name}' because no "
                                               'controller with this name exists'))
                    if strict:
                        log.append(LogLine('error', ABORT_STRICT))
                        return _fail(log)
                elif name not in lists[action]:
                    lists[action].append(name)
        act, deact = lists['activate'], lists['deactivate']
        for name in list(act):
            reason = None
            if name in self._active:
                reason = (f"Controller with name '{name}' is not inactive so its following controllers do not have "
                          'to be checked, because it cannot be activated.')
            elif self.specs[name].unavailable:
                reason = f"Controller with name '{name}' cannot be activated: {self.specs[name].unavailable}"
            if reason is not None:
                log.append(LogLine('warn', reason))
                log.append(LogLine('warn', f"Could not activate controller with name '{name}'. {_SEE_ABOVE}"))
                if strict:
                    log.append(LogLine('error', ABORT_STRICT))
                    return _fail(log)
                act.remove(name)
        for name in list(deact):
            if name not in self._active:
                log.append(LogLine('warn', f"Controller with name '{name}' can not be deactivated since it is not "
                                           'active.'))
                log.append(LogLine('warn', f"Could not deactivate controller with name '{name}'. {_SEE_ABOVE}"))
                if strict:
                    log.append(LogLine('error', ABORT_STRICT))
                    return _fail(log)
                deact.remove(name)
        # Resource conflicts: what stays claimed after the deactivations, plus what earlier activations claim.
        taken = {i: n for i, n in self.claimed_interfaces().items() if n not in deact}
        for name in list(act):
            clash = next((i for i in self.specs[name].command_interfaces if i in taken), None)
            if clash is not None:
                text = (f"Resource conflict for controller '{name}'. Command interface '{clash}' is already claimed "
                        f"(by '{taken[clash]}').")
                if strict:
                    log += [LogLine('error', text), LogLine('error', ABORT_STRICT)]
                    return _fail(log)
                log.append(LogLine('warn', text))
                act.remove(name)
                continue
            taken.update((i, name) for i in self.specs[name].command_interfaces)
        if not act and not deact:
            log.append(LogLine('info', EMPTY_SWITCH))
            return SwitchPlan(True, (), (), tuple(log))
        if self._mode_check is not None:
            start = tuple(i for n in act for i in self.specs[n].command_interfaces)
            stop = tuple(i for n in deact for i in self.specs[n].command_interfaces)
            reason = self._mode_check(start, stop, tuple(self.claimed_interfaces()))
            if reason is not None:
                log += [LogLine('error', reason), LogLine('error', HARDWARE_REJECTED)]
                return _fail(log)
        return SwitchPlan(True, tuple(deact), tuple(act), tuple(log))

    def apply(self, plan: SwitchPlan) -> None:
        """Record a planned switch as done (the caller runs the controllers' deactivate, then activate hooks).

        Raises:
            ValueError: the plan no longer fits the states (another switch came between plan and apply).
        """
        bad = [n for n in plan.deactivate if n not in self._active] + [n for n in plan.activate if n in self._active]
        if bad:
            raise ValueError(f"stale switch plan: '{bad[0]}' changed state since it was planned")
        self._active.difference_update(plan.deactivate)
        self._active.update(plan.activate)

    # ---- controller_stopper ----------------------------------------------------------------------------------------
    def stoppable_active(self) -> tuple[str, ...]:
        """The active controllers the driver's controller_stopper deactivates while the robot cannot move."""
        return tuple(n for n in self.active_names() if self.specs[n].stops_with_program)
