"""The controller manager's lifecycle services on its controllers: ``~/load_controller``, ``~/configure_controller``,
``~/cleanup_controller``, ``~/unload_controller`` and ``~/reload_controller_libraries``, on the manager's node.

The rules are ``controller_lifecycle.py``'s. ``load_controller`` reads ``<name>.type`` from the node's parameters
(declared for the driver's controllers, as its ``ur_controllers.yaml`` does) and loads the ur_sim controller of
that name and type: ur_sim has no plugin loader, so other names or types are refused, naming what it can load.
Unloading destroys the controller's node; loading creates it again. The trajectory controllers' action and topic
are served by the gateway process: while such a controller is not loaded they stay, and refuse as for an inactive
controller.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable

from controller_manager_msgs.srv import (
    CleanupController,
    ConfigureController,
    LoadController,
    ReloadControllerLibraries,
    UnloadController,
)

from ur_sim_driver.controllers import controller_lifecycle as lifecycle
from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.controller_manager import ControllerManager, ControllerSpec, LogLine


class LifecycleServices:
    """The lifecycle services on `node`, in callback `group`.

    Args:
        host: the simulation (its lock).
        manager: the controller manager core (the controllers' states).
        components: every controller ur_sim can load, by name (loaded or not).
        spec_of: a component's ControllerSpec.
        log: logs the manager's lines on its node.
        changed: called after a controller changed state (publishes ``~/activity``).
    """

    def __init__(self, node, group, host: Host, manager: ControllerManager, components: dict[str, Component],
                 spec_of: Callable[[Component], ControllerSpec], log: Callable[[Iterable[LogLine]], None],
                 changed: Callable[[], None]) -> None:
        self._node, self._host, self._manager, self._components = node, host, manager, components
        self._spec_of, self._log, self._changed = spec_of, log, changed
        for srv_type, name, callback in (
                (LoadController, 'load_controller', self._on_load),
                (ConfigureController, 'configure_controller', self._on_configure),
                (CleanupController, 'cleanup_controller', self._on_cleanup),
                (UnloadController, 'unload_controller', self._on_unload),
                (ReloadControllerLibraries, 'reload_controller_libraries', self._on_reload)):
            node.create_service(srv_type, f'~/{name}', callback, callback_group=group)

    def _on_load(self, request, response: LoadController.Response) -> LoadController.Response:
        name = request.name
        key = f'{name}.type'
        if not self._node.has_parameter(key):
            self._node.declare_parameter(key, '')
        type_name = self._node.get_parameter(key).value
        component = self._components.get(name)
        if not type_name:
            self._log([LogLine('error', f"The 'type' param was not defined for '{name}'.")])
        elif component is None or component.type_name != type_name:
            known = ', '.join(f"{c.name} ({c.type_name})" for c in self._components.values())
            self._log([LogLine('error', f"Loader for controller '{name}' (type '{type_name}') not found."),
                      LogLine('info', f'ur_sim has no plugin loader: it loads its controllers under their own names '
                                      f'and types: {known}')])
        else:
            with self._host.lock:
                step = lifecycle.load(self._manager, self._spec_of(component))
            self._log(step.log)
            if step.ok:
                component.configure(self._host)
                executor = self._node.executor
                if executor is not None:
                    executor.add_node(component.node)
                self._changed()
            response.ok = step.ok
        return response

    def _lifecycle(self, operation, name: str) -> bool:
        with self._host.lock:
            step = operation(self._manager, name)
        self._log(step.log)
        if step.ok:
            self._changed()
        return step.ok

    def _on_configure(self, request, response: ConfigureController.Response) -> ConfigureController.Response:
        response.ok = self._lifecycle(lifecycle.configure, request.name)
        return response

    def _on_cleanup(self, request, response: CleanupController.Response) -> CleanupController.Response:
        response.ok = self._lifecycle(lifecycle.cleanup, request.name)
        return response

    def _on_unload(self, request, response: UnloadController.Response) -> UnloadController.Response:
        response.ok = self._lifecycle(lifecycle.unload, request.name)
        component = self._components.get(request.name)
        if response.ok and component is not None:
            component.unload()
        return response

    def _on_reload(self, request, response: ReloadControllerLibraries.Response) -> ReloadControllerLibraries.Response:
        """ur_sim's controllers are built in: there is nothing to reload. With active controllers and no
        force_kill this is refused with upstream's words; with force_kill it is refused too, since upstream would
        deactivate and unload every controller and ur_sim has no libraries to load them from again."""
        active = self._manager.active_names()
        if active and not request.force_kill:
            text = (f'Controller manager: Cannot reload controller libraries because there are still {len(active)} '
                    'active controllers')
        elif active:
            text = ('ur_sim has no controller libraries to reload (its controllers are built in); force_kill would '
                    f'only deactivate and unload {len(active)} active controllers, so it is refused')
        else:
            text = 'ur_sim has no controller libraries to reload: its controllers are built in'
        self._log([LogLine('error' if active else 'info', text)])
        response.ok = not active
        return response
