"""Clients of ur_sim's controller manager for the tests (over DDS, on the harness's client node)."""
from __future__ import annotations

from builtin_interfaces.msg import Duration
from controller_manager_msgs.srv import (
    CleanupController,
    ConfigureController,
    ListControllers,
    ListControllerTypes,
    ListHardwareComponents,
    ListHardwareInterfaces,
    LoadController,
    SetHardwareComponentState,
    SwitchController,
    UnloadController,
)
from lifecycle_msgs.msg import State
from rclpy.callback_groups import ReentrantCallbackGroup
from sim_harness import SimHarness, wait_answer, wait_still

STRICT = SwitchController.Request.STRICT
BEST_EFFORT = SwitchController.Request.BEST_EFFORT


class ControllerManagerClient:
    """The controller manager services of one ur_sim."""

    def __init__(self, h: SimHarness) -> None:
        p = h.sim.cfg.prefixed
        group = ReentrantCallbackGroup()
        node = h.client
        self._list = node.create_client(ListControllers, p('controller_manager/list_controllers'),
                                        callback_group=group)
        self._switch = node.create_client(SwitchController, p('controller_manager/switch_controller'),
                                          callback_group=group)
        self._types = node.create_client(ListControllerTypes, p('controller_manager/list_controller_types'),
                                         callback_group=group)
        self._hardware = node.create_client(ListHardwareInterfaces, p('controller_manager/list_hardware_interfaces'),
                                            callback_group=group)
        self._lifecycle = {name: node.create_client(srv, p(f'controller_manager/{name}_controller'),
                                                    callback_group=group)
                           for name, srv in (('load', LoadController), ('configure', ConfigureController),
                                             ('cleanup', CleanupController), ('unload', UnloadController))}
        self._components = node.create_client(ListHardwareComponents,
                                              p('controller_manager/list_hardware_components'), callback_group=group)
        self._set_state = node.create_client(SetHardwareComponentState,
                                             p('controller_manager/set_hardware_component_state'),
                                             callback_group=group)
        for client in (self._list, self._switch, self._types, self._hardware, *self._lifecycle.values(),
                       self._components, self._set_state):
            wait_still(client.service_is_ready, what=f'the service {client.srv_name}')

    @staticmethod
    def _call(client, request):
        return wait_answer(client.call_async(request), f'the answer of {client.srv_name}')

    def switch(self, activate=(), deactivate=(), strictness=STRICT, timeout: float = 0.0):
        """The SwitchController response (ok, message)."""
        ns = round(timeout * 1e9)
        return self._call(self._switch, SwitchController.Request(
            activate_controllers=list(activate), deactivate_controllers=list(deactivate), strictness=strictness,
            timeout=Duration(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)))

    def controllers(self) -> dict:
        """name -> controller_manager_msgs/ControllerState, in the manager's order."""
        return {c.name: c for c in self._call(self._list, ListControllers.Request()).controller}

    def states(self) -> dict[str, str]:
        return {name: c.state for name, c in self.controllers().items()}

    def types(self):
        return self._call(self._types, ListControllerTypes.Request())

    def hardware(self):
        return self._call(self._hardware, ListHardwareInterfaces.Request())

    def lifecycle(self, operation: str, name: str) -> bool:
        """load, configure, cleanup or unload `name`: the answer's ok."""
        srv = {'load': LoadController, 'configure': ConfigureController, 'cleanup': CleanupController,
               'unload': UnloadController}[operation]
        return self._call(self._lifecycle[operation], srv.Request(name=name)).ok

    def components(self):
        """The controller_manager_msgs/HardwareComponentState of every hardware component."""
        return list(self._call(self._components, ListHardwareComponents.Request()).component)

    def set_component_state(self, name: str, state_id: int, label: str = ''):
        """The SetHardwareComponentState response (ok, state)."""
        return self._call(self._set_state, SetHardwareComponentState.Request(
            name=name, target_state=State(id=state_id, label=label)))
