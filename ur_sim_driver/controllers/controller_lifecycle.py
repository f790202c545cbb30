"""The controller manager's lifecycle services on its controllers, without ROS: load, configure, cleanup, unload.

Rules and wording from ros2_control jazzy 4.46 (``controller_manager.cpp``: ``load_controller``,
``configure_controller``, ``cleanup_controller``, ``unload_controller``):

* load adds the controller **unconfigured**; a name already loaded is refused;
* configure takes an unconfigured controller to inactive; an inactive one is cleaned up first and configured again;
  an active one is refused;
* cleanup takes an inactive controller back to unconfigured (an unconfigured one: nothing to do); an active one is
  refused;
* unload refuses an active controller; otherwise it cleans up, shuts down (finalized) and removes it.

Each returns a :class:`Step`: the service's ``ok`` and what the manager logs. The node creates and destroys the
controllers' ROS interfaces around these calls.
"""
from __future__ import annotations

from dataclasses import dataclass

from ur_sim_driver.controllers.controller_manager import (
    ACTIVE,
    INACTIVE,
    UNCONFIGURED,
    ControllerManager,
    ControllerSpec,
    LogLine,
)


@dataclass(frozen=True)
class Step:
    """The answer of a lifecycle service: `ok` and the lines logged, in order."""

    ok: bool
    log: tuple[LogLine, ...]


def _refuse(*lines: LogLine) -> Step:
    return Step(False, lines)


def _unknown(action: str, name: str) -> Step:
    return _refuse(LogLine('error', f"Could not {action} controller with name '{name}' because no controller with "
                                    'this name exists'))


def load(cm: ControllerManager, spec: ControllerSpec) -> Step:
    """Add `spec`, unconfigured, after the loaded ones."""
    head = LogLine('info', f"Loading controller '{spec.name}'")
    if spec.name in cm.specs:
        return _refuse(head, LogLine('error', f"A controller named '{spec.name}' was already loaded inside the "
                                              'controller manager'))
    cm.specs[spec.name] = spec
    cm.states[spec.name] = UNCONFIGURED
    return Step(True, (head,))


def configure(cm: ControllerManager, name: str) -> Step:
    """unconfigured (or inactive, cleaned up first) -> inactive."""
    head = LogLine('info', f"Configuring controller: '{name}'")
    if name not in cm.specs:
        return _unknown('configure', name)
    state = cm.states[name]
    if state == ACTIVE:
        return _refuse(head, LogLine('error', f"Controller '{name}' can not be configured from '{state}' state."))
    log = [head]
    if state == INACTIVE:
        log.append(LogLine('info', f"Controller '{name}' is cleaned-up before configuring"))
    cm.states[name] = INACTIVE
    return Step(True, tuple(log))


def cleanup(cm: ControllerManager, name: str) -> Step:
    """inactive -> unconfigured (unconfigured stays)."""
    if name not in cm.specs:
        return _unknown('cleanup', name)
    state = cm.states[name]
    if state == ACTIVE:
        return _refuse(LogLine('error', f"Controller '{name}' can not be cleaned-up from '{state}' state."))
    cm.states[name] = UNCONFIGURED
    return Step(True, (LogLine('info', f"Cleaning up controller '{name}'"),) if state == INACTIVE else ())


def unload(cm: ControllerManager, name: str) -> Step:
    """Remove a controller that is not active."""
    head = LogLine('info', f"Unloading controller: '{name}'")
    if name not in cm.specs:
        return Step(False, (head,) + _unknown('unload', name).log)
    if cm.states[name] == ACTIVE:
        return _refuse(head, LogLine('error', f"Could not unload controller with name '{name}' because it is still "
                                              'active'))
    del cm.specs[name]
    del cm.states[name]
    return Step(True, (head,))
