"""The ``controller_manager`` node: ros2_control's services over ur_sim's controllers.

Services (controller_manager_msgs): ``~/list_controllers``, ``~/switch_controller``, ``~/list_controller_types``,
``~/list_hardware_interfaces``. The loaded controllers are ur_sim's components, in their order; the rules are
``controller_manager.py``'s. A switch is decided and done by the simulation loop between two control cycles
(:meth:`ControllerManagerNode.apply_pending`, under the simulation lock): the service hands the request over and
waits until it is done, and until the trajectory controllers' gateway knows, so that a goal sent after the answer
meets the new states. ``timeout`` bounds that wait (0: no bound); a request the loop has not taken by then is
dropped and answered ``ok = False``. ``activate_asap`` changes nothing here: activation needs no hardware start-up,
every switch happens at the next cycle.

The driver's controller_stopper is here too (:meth:`program_state_changed`): while the robot cannot move, the
active controllers that command it are deactivated; when it can again, they are activated again.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from controller_manager_msgs.msg import ControllerState, HardwareInterface
from controller_manager_msgs.srv import ListControllers, ListControllerTypes, ListHardwareInterfaces, SwitchController
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup

from ur_sim_driver.controllers import ur_hardware
from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.controllers.controller_manager import BEST_EFFORT, ControllerManager, ControllerSpec, SwitchPlan
from ur_sim_driver.motion import conversions as conv

NAME = 'controller_manager'
BASE_CLASS = 'controller_interface::ControllerInterface'
TIMED_OUT = 'Switch controller request timed out before the control loop took it; nothing was switched.'


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
    """The manager of `components` (every controller of ur_sim, broadcasters included).

    Args:
        host: what the components were configured with.
        components: the loaded controllers, in load order; their `initially_active` decide the start states.
    """

    def __init__(self, host: Host, components: list[Component]) -> None:
        self.host = host
        self.components = {c.name: c for c in components}
        cfg = host.cfg
        specs = []
        for c in components:
            command, state = c.interfaces(cfg)
            specs.append(ControllerSpec(c.name, c.type_name, command, state, getattr(c, 'unavailable', None),
                                        stops_with_program=bool(command)))
        self.manager = ControllerManager(
            specs, [c.name for c in components if c.initially_active],
            lambda start, stop, running: ur_hardware.prepare_command_mode_switch(start, stop, running, cfg.tf_prefix))
        joints = ur_hardware.prefixed_joints(cfg.joints, cfg.tf_prefix)
        self._command_interfaces = _union(ur_hardware.command_interfaces(joints, cfg.tf_prefix),
                                          *(s.command_interfaces for s in specs))
        self._state_interfaces = _union(ur_hardware.state_interfaces(joints, cfg.tf_prefix),
                                        *(s.state_interfaces for s in specs))
        self._update_rate = int(round(host.sim.control_rate))
        self._pending: list[_Request] = []
        self._pending_lock = threading.Lock()
        self._stopped: tuple[str, ...] = ()
        self.node = host.create_node(NAME)
        p = cfg.prefixed
        queries = MutuallyExclusiveCallbackGroup()
        self.node.create_service(ListControllers, p(f'{NAME}/list_controllers'), self._on_list, callback_group=queries)
        self.node.create_service(ListControllerTypes, p(f'{NAME}/list_controller_types'), self._on_types,
                                 callback_group=queries)
        self.node.create_service(ListHardwareInterfaces, p(f'{NAME}/list_hardware_interfaces'), self._on_hardware,
                                 callback_group=queries)
        # Reentrant: a switch waits for the loop; list requests must not queue behind it.
        self.node.create_service(SwitchController, p(f'{NAME}/switch_controller'), self._on_switch,
                                 callback_group=ReentrantCallbackGroup())
        self._switch_lock = threading.Lock()  # one switch at a time, as upstream's services lock

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
            self._log_info(f'controller_stopper: deactivating {", ".join(names)} ({refusal})')
            self._switch((), names, BEST_EFFORT)
        elif self._stopped:
            names, self._stopped = self._stopped, ()
            self._log_info(f'controller_stopper: activating {", ".join(names)} again')
            self._switch(names, (), BEST_EFFORT)

    def _switch(self, activate, deactivate, strictness) -> SwitchPlan:
        plan = self.manager.plan(activate, deactivate, strictness)
        logger = self.node.get_logger()
        for line in plan.log:
            # One call site per severity: rclpy refuses a call site whose severity changes.
            if line.level == 'error':
                logger.error(line.text)
            elif line.level == 'warn':
                logger.warning(line.text)
            else:
                logger.info(line.text)
        if plan.ok and (plan.activate or plan.deactivate):
            for name in plan.deactivate:
                self.components[name].deactivate()
            for name in plan.activate:
                self.components[name].activate()
            self.manager.apply(plan)
        return plan

    def _log_info(self, text: str) -> None:
        self.node.get_logger().info(text)

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
            states = {n: (self.manager.state(n), self.manager.claimed(n)) for n in self.components}
        for name, spec in self.manager.specs.items():
            state, claimed = states[name]
            response.controller.append(ControllerState(
                name=name, state=state, type=spec.type_name, is_async=False, update_rate=self._update_rate,
                claimed_interfaces=list(claimed), required_command_interfaces=list(spec.command_interfaces),
                required_state_interfaces=list(spec.state_interfaces), is_chainable=False, is_chained=False))
        return response

    def _on_types(self, request, response: ListControllerTypes.Response) -> ListControllerTypes.Response:
        types = sorted({spec.type_name for spec in self.manager.specs.values()})
        response.types = types
        response.base_classes = [BASE_CLASS] * len(types)
        return response

    def _on_hardware(self, request, response: ListHardwareInterfaces.Response) -> ListHardwareInterfaces.Response:
        with self.host.lock:
            claimed = set(self.manager.claimed_interfaces())
        response.command_interfaces = [HardwareInterface(name=n, data_type='double', is_available=True,
                                                         is_claimed=n in claimed) for n in self._command_interfaces]
        response.state_interfaces = [HardwareInterface(name=n, data_type='double', is_available=True,
                                                       is_claimed=False) for n in self._state_interfaces]
        return response

    def destroy(self) -> None:
        self.node.destroy_node()


def _union(*groups) -> tuple[str, ...]:
    return tuple(dict.fromkeys(name for group in groups for name in group))
