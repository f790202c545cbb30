"""The ``controller_manager`` node: ros2_control's services over ur_sim's controllers and its hardware component.

Services (controller_manager_msgs), as ros2_control jazzy offers them: ``~/list_controllers``,
``~/list_controller_types``, ``~/switch_controller``, ``~/load_controller``, ``~/configure_controller``,
``~/cleanup_controller``, ``~/unload_controller``, ``~/reload_controller_libraries`` (``lifecycle_services.py``),
the hardware's (``hardware_services.py``); the topic ``~/activity`` (every lifecycle change of a controller or the
hardware).

The loaded controllers are ur_sim's components, in their order; the rules are ``controller_manager.py``'s and
``controller_lifecycle.py``'s. A switch is decided and done by the simulation loop between two control cycles
(:meth:`ControllerManagerNode.apply_pending`, under the simulation lock): the service hands the request over and
waits until it is done, and until the trajectory controllers' gateway knows, so that a goal sent after the answer
meets the new states. ``timeout`` bounds that wait (0: no bound); a request the loop has not taken by then is
dropped and answered ``ok = False``. ``activate_asap`` changes nothing here: every switch happens at the next cycle.

The driver's controller_stopper is here too (:meth:`program_state_changed`): while the robot cannot move, the
active controllers outside its consistent list (``startup.CONSISTENT``) are deactivated; when it can again, they
are activated again.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from controller_manager_msgs.msg import ControllerManagerActivity, ControllerState, NamedLifecycleState
from controller_manager_msgs.srv import ListControllers, ListControllerTypes, SwitchController
from lifecycle_msgs.msg import State
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ur_sim_driver.controllers import hardware_component as hwc
from ur_sim_driver.controllers import startup, ur_hardware
from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.controller_manager import (
    ACTIVE,
    BEST_EFFORT,
    INACTIVE,
    ControllerManager,
    ControllerSpec,
    SwitchPlan,
)
from ur_sim_driver.controllers.hardware_services import HardwareServices
from ur_sim_driver.controllers.lifecycle_services import LifecycleServices
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
            hwc.IDS[cfg.hardware_components_initial_state],
            check=lambda _name, step: startup.configure_refusal(cfg) if step == hwc.CONFIGURE else None)
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
        self.node.create_service(ListControllers, '~/list_controllers', self._on_list, callback_group=queries)
        self.node.create_service(ListControllerTypes, '~/list_controller_types', self._on_types,
                                 callback_group=queries)
        self.lifecycle_services = LifecycleServices(self.node, queries, host, self.manager, self.components,
                                                    self._spec, self.log, self.publish_activity)
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
        msg.header.stamp = self.host.clock.stamp(self.host.sim.time)
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

    def destroy(self) -> None:
        self.node.destroy_node()


def _union(*groups) -> tuple[str, ...]:
    return tuple(dict.fromkeys(name for group in groups for name in group))
