"""The hardware component's lifecycle as ros2_control's resource manager drives it, without ROS.

The UR driver runs one hardware component (``<ros2_control name="<ur_type>" type="system">``, plugin
``ur_robot_driver/URPositionHardwareInterface``). ``set_hardware_component_state`` moves it between the primary
lifecycle states; facts from ros2_control jazzy 4.46 (``resource_manager.cpp``: ``set_component_state`` and the
interface bookkeeping of each transition; ``hardware_component.cpp``):

* the transitions from each state to each target (:data:`_STEPS`): configure, activate, deactivate, cleanup,
  shutdown, run in order; the request succeeds only when every step does; a finalized component can only be
  destroyed;
* configure makes all of the component's interfaces available, cleanup and shutdown make them unavailable;
  activate and deactivate do not change them (an inactive component's interfaces stay available: a TODO upstream);
* ``read()`` runs while inactive or active, ``write()`` only while active (:attr:`HardwareComponent.reads`,
  :attr:`HardwareComponent.writes`);
* a controller that claims command interfaces cannot be activated while the component is inactive
  (``allow_controller_activation_with_inactive_hardware`` is false by default).

What a transition does to the simulated robot is the node's business (``controller_manager_node.py``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

UNKNOWN, UNCONFIGURED, INACTIVE, ACTIVE, FINALIZED = 0, 1, 2, 3, 4
LABELS = {UNKNOWN: 'unknown', UNCONFIGURED: 'unconfigured', INACTIVE: 'inactive', ACTIVE: 'active',
          FINALIZED: 'finalized'}
IDS = {label: i for i, label in LABELS.items() if i != UNKNOWN}
CONFIGURE, ACTIVATE, DEACTIVATE, CLEANUP, SHUTDOWN = 'configure', 'activate', 'deactivate', 'cleanup', 'shutdown'
# The state each transition reaches when it succeeds.
_REACHES = {CONFIGURE: INACTIVE, ACTIVATE: ACTIVE, DEACTIVATE: INACTIVE, CLEANUP: UNCONFIGURED, SHUTDOWN: FINALIZED}
# (current, target) -> the transitions that lead there; missing pairs from FINALIZED are refused.
_STEPS = {
    (UNCONFIGURED, UNCONFIGURED): (), (UNCONFIGURED, INACTIVE): (CONFIGURE,),
    (UNCONFIGURED, ACTIVE): (CONFIGURE, ACTIVATE), (UNCONFIGURED, FINALIZED): (SHUTDOWN,),
    (INACTIVE, UNCONFIGURED): (CLEANUP,), (INACTIVE, INACTIVE): (), (INACTIVE, ACTIVE): (ACTIVATE,),
    (INACTIVE, FINALIZED): (SHUTDOWN,),
    (ACTIVE, UNCONFIGURED): (DEACTIVATE, CLEANUP), (ACTIVE, INACTIVE): (DEACTIVATE,), (ACTIVE, ACTIVE): (),
    (ACTIVE, FINALIZED): (DEACTIVATE, SHUTDOWN),
    (FINALIZED, FINALIZED): (),
}

# A transition's own check: (component name, transition) -> None, or why it fails (the component stays put).
TransitionCheck = Callable[[str, str], 'str | None']


@dataclass(frozen=True)
class Transition:
    """What one set_component_state request did.

    Attributes:
        ok: every step reached its state (the service's ``ok``).
        steps: the transitions run, in order (the failed one last).
        log: (level, text) lines, in order, with the resource manager's words.
    """

    ok: bool
    steps: tuple[str, ...]
    log: tuple[tuple[str, str], ...]


class HardwareComponent:
    """One ros2_control hardware component.

    Args:
        name: its ``<ros2_control name>`` (the UR driver's: the ur_type).
        plugin_name: its ``<hardware><plugin>``.
        command_interfaces, state_interfaces: what it exports, in export order.
        state: its state at start (ros2_control configures and activates components not named otherwise).
        check: the component's own check of a transition (e.g. the driver's robot model check on configure).
    """

    type_name = 'system'

    def __init__(self, name: str, plugin_name: str, command_interfaces: tuple[str, ...],
                 state_interfaces: tuple[str, ...], state: int = ACTIVE, check: TransitionCheck | None = None) -> None:
        if state not in (UNCONFIGURED, INACTIVE, ACTIVE):
            raise ValueError(f'initial hardware state {state} is not one of unconfigured (1), inactive (2), '
                             f'active (3)')
        self.name = name
        self.plugin_name = plugin_name
        self.command_interfaces = command_interfaces
        self.state_interfaces = state_interfaces
        self.state = state
        self._check = check

    @property
    def label(self) -> str:
        return LABELS[self.state]

    @property
    def available(self) -> bool:
        """Its interfaces are available (configured, not cleaned up or shut down)."""
        return self.state in (INACTIVE, ACTIVE)

    @property
    def reads(self) -> bool:
        """``read()`` runs each cycle: the state interfaces follow the robot."""
        return self.state in (INACTIVE, ACTIVE)

    @property
    def writes(self) -> bool:
        """``write()`` runs each cycle: commands reach the robot."""
        return self.state == ACTIVE

    def rejects_start(self, start: tuple[str, ...]) -> str | None:
        """The resource manager's refusal to start command interfaces of this component now, or None."""
        mine = [i for i in start if i in self.command_interfaces]
        if mine and self.state == INACTIVE:
            return (f"Component '{self.name}' is in INACTIVE state, but has start interfaces to switch: "
                    + ' '.join(mine))
        return None

    def set_state(self, target_id: int, target_label: str = '') -> Transition:
        """Move towards `target_id` (0: the state named by `target_label`), as set_component_state does."""
        if target_id == UNKNOWN:
            target_id = IDS.get(target_label, UNKNOWN)
        if self.state == FINALIZED and target_id != FINALIZED and target_id in LABELS:
            text = f"hardware '{self.name}' is in finalized state and can be only destroyed."
            return Transition(False, (), (('warn', text),))
        steps = _STEPS.get((self.state, target_id))
        if steps is None:
            valid = ', '.join(f'{label} ({i})' for label, i in IDS.items())
            return Transition(False, (), (('error', f"target state {target_id} '{target_label}' of hardware "
                                                    f"'{self.name}' is not a primary state; valid: {valid}"),))
        log: list[tuple[str, str]] = []
        done: list[str] = []
        for step in steps:
            done.append(step)
            log.append(('info', f"'{step}' hardware '{self.name}' "))
            reason = self._check(self.name, step) if self._check is not None else None
            if reason is not None:
                log.append(('error', reason))
                log.append(('error', f"Failed to '{step}' hardware '{self.name}'"))
                return Transition(False, tuple(done), tuple(log))
            self.state = _REACHES[step]
            log.append(('info', f"Successful '{step}' of hardware '{self.name}'"))
        return Transition(True, tuple(done), tuple(log))
