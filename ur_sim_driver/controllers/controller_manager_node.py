"""The ``controller_manager`` node: ros2_control's services over ur_sim's controllers and its hardware component.

Services (controller_manager_msgs), as ros2_control jazzy offers them: ``~/list_controllers``,
``~/list_controller_types``, ``~/switch_controller``, ``~/load_controller``, ``~/configure_controller``,
``~/cleanup_controller``, ``~/unload_controller``, ``~/reload_controller_libraries``, and the hardware's
(``hardware_services.py``); the topic ``~/activity`` (every lifecycle change of a controller or the hardware).

The loaded controllers are ur_sim's components, in their order; the rules are ``controller_manager.py``'s and
``controller_lifecycle.py``'s. A switch is decided and done by the simulation loop between two control cycles
(:meth:`ControllerManagerNode.apply_pending`, under the simulation lock): the service hands the request over and
waits until it is done, and until the trajectory controllers' gateway knows, so that a goal sent after the answer
meets the new states. ``timeout`` bounds that wait (0: no bound); a request the loop has not taken by then is
dropped and answered ``ok = False``. ``activate_asap`` changes nothing here: every switch happens at the next cycle.

``load_controller`` reads ``<name>.type`` from this node's parameters (declared for the driver's controllers, as
its ``ur_controllers.yaml`` does) and loads the ur_sim controller of that name and type: ur_sim has no plugin
loader, so other names or types are refused, naming what it can load. Unloading destroys the controller's node;
loading creates it again. The trajectory controllers' action and topic are served by the gateway process: while
such a controller is not loaded they stay, and refuse as for an inactive controller.

The driver's controller_stopper is here too (:meth:`program_state_changed`): while the robot cannot move, the
active controllers that command it are deactivated; when it can again, they are activated again.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from controller_manager_msgs.msg import ControllerManagerActivity, ControllerState, NamedLifecycleState
from controller_manager_msgs.srv import (
    CleanupController,
    ConfigureController,
    ListControllers,
    ListControllerTypes,
    LoadController,
    ReloadControllerLibraries,
    SwitchController,
    UnloadController,
)
from lifecycle_msgs.msg import State
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ur_sim_driver.controllers import controller_lifecycle as lifecycle
from ur_sim_driver.controllers import hardware_component as hwc
from ur_sim_driver.controllers import startup, ur_hardware
from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.controller_manager import (
    ACTIVE,
    BEST_EFFORT,
    INACTIVE,
    ControllerManager,
    ControllerSpec,
    LogLine,
    SwitchPlan,
)
from ur_sim_driver.controllers.hardware_services import HardwareServices
from ur_sim_driver.motion import conversions as conv

NAME = 'controller_manager'
BASE_CLASS = 'controller_interface::ControllerInterface'
TIMED_OUT = 'Switch controller request timed out before the control loop took it; nothing was switched.'
PLUGIN = 'ur_robot_driver/URPositionHardwareInterface'
_CONTROLLER_IDS = {'unconfigured': State.PRIMARY_STATE_UNCONFIGURED, INACTIVE: State.PRIMARY_STATE_INACTIVE,
                   ACTIVE: State.PRIMARY_STATE_ACTIVE}


@dataclass
class _Request:
    activate: tuple[str, ...]
    deactivate: tuple[str, ...]
    strictness: int
    lock: threading.Lock = field(default_factory=threading.Lock)
    taken: bool = False
    cancelled: bool = False
    done: threading.Event = field(default_factory=threading.Event)
    plan: SwitchPlan | None = None


class ControllerManagerNode:
    """The manager of `components` (every controller of ur_sim, broadcasters included) and the hardware.

    Args:
        host: what the components were configured with.
        components: the loaded controllers, in load order; their `initially_active` decide the start states.
    """

    def __init__(self, host: Host, components: list[Component]) -> None:
        self.host = host
        self.components = {c.name: c for c in components}  # every controller ur_sim can load, loaded or not
        cfg = host.cfg
        specs = [self._spec(c) for c in components]
        joints = ur_hardware.prefixed_joints(cfg.joints, cfg.tf_prefix)
        self.hardware = hwc.HardwareComponent(
            cfg.ur_type, PLUGIN,
            _union(ur_hardware.command_interfaces(joints, cfg.tf_prefix), *(s.command_interfaces for s in specs)),
            _union(ur_hardware.state_interfaces(joints, cfg.tf_prefix), *(s.state_interfaces for s in specs)),
            hwc.IDS[cfg.hardware_components_initial_state])
        self.manager = ControllerManager(
            specs, [c.name for c in components if c.initially_active],
            lambda start, stop, running: ur_hardware.prepare_command_mode_switch(start, stop, running, cfg.tf_prefix,
                                                                                 cfg.software_version),
            self.hardware)
        self.update_rate = int(round(host.sim.control_rate))
        self._pending: list[_Request] = []
        self._pending_lock = threading.Lock()
        self._stopped: tuple[str, ...] = ()
        self.node = host.create_node(NAME, parameter_services=True)
        self.node.declare_parameter('update_rate', self.update_rate)
        for c in components:
            self.node.declare_parameter(f'{c.name}.type', c.type_name)
        self._activity = self.node.create_publisher(
            ControllerManagerActivity, '~/activity',
            QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        queries = MutuallyExclusiveCallbackGroup()
        for srv_type, name, callback in (
                (ListControllers, 'list_controllers', self._on_list),
                (ListControllerTypes, 'list_controller_types', self._on_types),
                (LoadController, 'load_controller', self._on_load),
                (ConfigureController, 'configure_controller', self._on_configure),
                (CleanupController, 'cleanup_controller', self._on_cleanup),
                (UnloadController, 'unload_controller', self._on_unload),
                (ReloadControllerLibraries, 'reload_controller_libraries', self._on_reload)):
            self.node.create_service(srv_type, f'~/{name}', callback, callback_group=queries)
        self.hardware_services = HardwareServices(self.node, queries, host, self.manager, self.update_rate, self.log,
                                                  self.publish_activity)
        # Reentrant: a switch waits for the loop; list requests must not queue behind it.
        self.node.create_service(SwitchController, '~/switch_controller', self._on_switch,
                                 callback_group=ReentrantCallbackGroup())
        self._switch_lock = threading.Lock()  # one switch at a time, as upstream's services lock
        self.publish_activity()

    def _spec(self, c: Component) -> ControllerSpec:
        command, state = c.interfaces(self.host.cfg)
        return ControllerSpec(c.name, c.type_name, command, state, getattr(c, 'unavailable', None),
                              stops_with_program=c.name not in startup.CONSISTENT)

    @property
    def pending(self) -> bool:
        """A switch request waits for the next cycle (a script that steps the simulation itself steps then)."""
        return bool(self._pending)

    # ---- simulation loop, under the lock ---------------------------------------------------------------------------
    def apply_pending(self) -> None:
        """Decide and do the switches requested since the last cycle."""
        if not self._pending:
            return
        with self._pending_lock:
            requests, self._pending = self._pending, []
        for req in requests:
            with req.lock:
                if req.cancelled:
                    continue
                req.taken = True
            req.plan = self._switch(req.activate, req.deactivate, req.strictness)
            req.done.set()

    def program_state_changed(self, refusal: str | None) -> None:
        """The driver's controller_stopper: `refusal` is why the robot cannot move now, or None when it can."""
        if refusal is not None:
            names = self.manager.stoppable_active()
            if not names:
                return
            for name in names:
                self.components[name].stop_reason = refusal
            self._stopped = tuple(dict.fromkeys(self._stopped + names))
            self.node.get_logger().info(f'controller_stopper: deactivating {", ".join(names)} ({refusal})')
            self._switch((), names, BEST_EFFORT)
        elif self._stopped:
            names, self._stopped = self._stopped, ()
            self.node.get_logger().info(f'controller_stopper: activating {", ".join(names)} again')
            self._switch(names, (), BEST_EFFORT)

    def _switch(self, activate, deactivate, strictness) -> SwitchPlan:
        plan = self.manager.plan(activate, deactivate, strictness)
        self.log(plan.log)
        if plan.activate or plan.deactivate:
            for name in plan.deactivate:
                self.components[name].deactivate()
            for name in plan.activate:
                self.components[name].activate()
            self.manager.apply(plan)
            self.publish_activity()
        return plan

    def log(self, lines) -> None:
        logger = self.node.get_logger()
        for line in lines:
            # One call site per severity: rclpy refuses a call site whose severity changes.
            if line.level == 'error':
                logger.error(line.text)
            elif line.level == 'warn':
                logger.warning(line.text)
            else:
                logger.info(line.text)

    def publish_activity(self) -> None:
        """``~/activity``: the states of every controller and of the hardware component."""
        msg = ControllerManagerActivity()
        msg.header.stamp = conv.sec_to_time(self.host.sim.time)
        msg.controllers = [NamedLifecycleState(name=n, state=State(id=_CONTROLLER_IDS[s], label=s))
                           for n, s in self.manager.states.items()]
        msg.hardware_components = [NamedLifecycleState(name=self.hardware.name, state=State(
            id=self.hardware.state, label=self.hardware.label))]
        self._activity.publish(msg)

    # ---- services (executor threads) ----------------------------------------------------------------------------
    def _on_switch(self, request: SwitchController.Request,
                   response: SwitchController.Response) -> SwitchController.Response:
        timeout = conv.duration_to_sec(request.timeout)
        req = _Request(tuple(request.activate_controllers), tuple(request.deactivate_controllers),
                       int(request.strictness))
        with self._switch_lock:
            with self._pending_lock:
                self._pending.append(req)
            deadline = time.monotonic() + timeout if timeout > 0.0 else None
            while not req.done.wait(0.05):
                if not self.host.context.ok():
                    break
                if deadline is not None and time.monotonic() > deadline:
                    with req.lock:
                        if not req.taken:
                            req.cancelled = True
                            break
            plan = req.plan
            if plan is None:
                self.node.get_logger().error(TIMED_OUT)
                response.ok, response.message = False, TIMED_OUT
                return response
        response.ok, response.message = plan.ok, plan.message
        return response

    def _on_list(self, request, response: ListControllers.Response) -> ListControllers.Response:
        with self.host.lock:
            rows = [(spec, self.manager.state(n), self.manager.claimed(n)) for n, spec in self.manager.specs.items()]
        for spec, state, claimed in rows:
            configured = state != 'unconfigured'  # required interfaces are known once configured
            response.controller.append(ControllerState(
                name=spec.name, state=state, type=spec.type_name, is_async=False, update_rate=self.update_rate,
                claimed_interfaces=list(claimed),
                required_command_interfaces=list(spec.command_interfaces) if configured else [],
                required_state_interfaces=list(spec.state_interfaces) if configured else [],
                is_chainable=False, is_chained=False))
        return response

    def _on_types(self, request, response: ListControllerTypes.Response) -> ListControllerTypes.Response:
        types = sorted({c.type_name for c in self.components.values()})
        response.types = types
        response.base_classes = [BASE_CLASS] * len(types)
        return response

    def _on_load(self, request, response: LoadController.Response) -> LoadController.Response:
        name = request.name
        key = f'{name}.type'
        if not self.node.has_parameter(key):
            self.node.declare_parameter(key, '')
        type_name = self.node.get_parameter(key).value
        component = self.components.get(name)
        if not type_name:
            self.log([LogLine('error', f"The 'type' param was not defined for '{name}'.")])
        elif component is None or component.type_name != type_name:
            known = ', '.join(f"{c.name} ({c.type_name})" for c in self.components.values())
            self.log([LogLine('error', f"Loader for controller '{name}' (type '{type_name}') not found."),
                      LogLine('info', f'ur_sim has no plugin loader: it loads its controllers under their own names '
                                      f'and types: {known}')])
        else:
            with self.host.lock:
                step = lifecycle.load(self.manager, self._spec(component))
            self.log(step.log)
            if step.ok:
                component.configure(self.host)
                executor = self.node.executor
                if executor is not None:
                    executor.add_node(component.node)
                self.publish_activity()
            response.ok = step.ok
        return response

    def _lifecycle(self, operation, name: str) -> bool:
        with self.host.lock:
            step = operation(self.manager, name)
        self.log(step.log)
        if step.ok:
            self.publish_activity()
        return step.ok

    def _on_configure(self, request, response: ConfigureController.Response) -> ConfigureController.Response:
        response.ok = self._lifecycle(lifecycle.configure, request.name)
        return response

    def _on_cleanup(self, request, response: CleanupController.Response) -> CleanupController.Response:
        response.ok = self._lifecycle(lifecycle.cleanup, request.name)
        return response

    def _on_unload(self, request, response: UnloadController.Response) -> UnloadController.Response:
        response.ok = self._lifecycle(lifecycle.unload, request.name)
        component = self.components.get(request.name)
        if response.ok and component is not None:
            component.unload()
        return response

    def _on_reload(self, request, response: ReloadControllerLibraries.Response) -> ReloadControllerLibraries.Response:
        """ur_sim's controllers are built in: there is nothing to reload. With active controllers and no
        force_kill this is refused with upstream's words; with force_kill it is refused too, since upstream would
        deactivate and unload every controller and ur_sim has no libraries to load them from again."""
        active = self.manager.active_names()
        if active and not request.force_kill:
            text = (f'Controller manager: Cannot reload controller libraries because there are still {len(active)} '
                    'active controllers')
        elif active:
            text = ('ur_sim has no controller libraries to reload (its controllers are built in); force_kill would '
                    f'only deactivate and unload {len(active)} active controllers, so it is refused')
        else:
            text = 'ur_sim has no controller libraries to reload: its controllers are built in'
        self.log([LogLine('error' if active else 'info', text)])
        response.ok = not active
        return response

    def destroy(self) -> None:
        self.node.destroy_node()


def _union(*groups) -> tuple[str, ...]:
    return tuple(dict.fromkeys(name for group in groups for name in group))
