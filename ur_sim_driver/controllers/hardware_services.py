"""The controller manager's hardware services: ``~/list_hardware_components``, ``~/set_hardware_component_state``
and ``~/list_hardware_interfaces``, on the controller manager's node.

ros2_control jazzy 4.46 (``controller_manager.cpp``): components are listed with name, type ``system``, plugin
name, lifecycle state and every interface with ``is_available`` and ``is_claimed`` (an unavailable command interface
is never claimed; a state interface is never claimed); ``class_type`` (deprecated) stays empty. Interfaces are
listed sorted by name, as the resource manager's maps hold them.

What the hardware's state does to the simulated robot, as the UR driver's hardware interface does it:

* **active**: ``read()`` and ``write()`` run: the controllers' commands reach the robot;
* **inactive**: ``read()`` runs, ``write()`` does not: no command reaches the robot. A running External Control
  program, which was receiving commands, times out on its reverse socket and exits (``external_control.urscript``:
  "Socket timed out waiting for command on reverse_socket. The script will exit now.") and the robot holds. A
  program started while inactive waits for its first command (that first read blocks);
* **unconfigured** (cleanup: the driver disconnects): nothing is read either; the broadcasters keep publishing the
  last values read. A running program loses its connection and ends. Configuring again connects; the program must
  be started again (play, or resend_robot_program).
"""
from __future__ import annotations

from collections.abc import Callable, Iterable

from controller_manager_msgs.msg import HardwareComponentState, HardwareInterface
from controller_manager_msgs.srv import ListHardwareComponents, ListHardwareInterfaces, SetHardwareComponentState
from lifecycle_msgs.msg import State

from ur_sim_driver.controllers.base import Host
from ur_sim_driver.controllers.controller_manager import ControllerManager, LogLine

SCRIPT_EXIT = 'Socket timed out waiting for command on reverse_socket. The script will exit now.'
DISCONNECTED = 'the driver closed its reverse interface; the External Control program ends'


class HardwareServices:
    """The hardware services on `node`, in callback `group`.

    Args:
        host: the simulation (its lock and robot).
        manager: the controller manager core (its hardware component and the controllers' claims).
        rw_rate: the component's read/write rate [Hz] (the controller manager's: the driver leaves it 0).
        log: logs the manager's lines on its node.
        changed: called after the component changed state (publishes ``~/activity``).
    """

    def __init__(self, node, group, host: Host, manager: ControllerManager, rw_rate: int,
                 log: Callable[[Iterable[LogLine]], None], changed: Callable[[], None]) -> None:
        self._host, self._manager, self._rw_rate, self._log, self._changed = host, manager, rw_rate, log, changed
        node.create_service(ListHardwareComponents, '~/list_hardware_components', self._on_components,
                            callback_group=group)
        node.create_service(SetHardwareComponentState, '~/set_hardware_component_state', self._on_set_state,
                            callback_group=group)
        node.create_service(ListHardwareInterfaces, '~/list_hardware_interfaces', self._on_interfaces,
                            callback_group=group)

    def _interfaces(self) -> tuple[list[HardwareInterface], list[HardwareInterface]]:
        """(command, state) interfaces of the component, in export order; under the lock."""
        manager = self._manager
        hw = manager.hardware
        command = [HardwareInterface(name=n, data_type='double', is_available=hw.available,
                                     is_claimed=manager.is_claimed(n)) for n in hw.command_interfaces]
        state = [HardwareInterface(name=n, data_type='double', is_available=hw.available, is_claimed=False)
                 for n in hw.state_interfaces]
        return command, state

    def _on_components(self, request, response: ListHardwareComponents.Response) -> ListHardwareComponents.Response:
        hw = self._manager.hardware
        with self._host.lock:
            command, state = self._interfaces()
            lifecycle = State(id=hw.state, label=hw.label)
        response.component = [HardwareComponentState(
            name=hw.name, type=hw.type_name, is_async=False, rw_rate=self._rw_rate, class_type='',
            plugin_name=hw.plugin_name, state=lifecycle, command_interfaces=command, state_interfaces=state)]
        return response

    def _on_interfaces(self, request, response: ListHardwareInterfaces.Response) -> ListHardwareInterfaces.Response:
        with self._host.lock:
            command, state = self._interfaces()
        response.command_interfaces = sorted(command, key=lambda i: i.name)
        response.state_interfaces = sorted(state, key=lambda i: i.name)
        return response

    def _on_set_state(self, request, response: SetHardwareComponentState.Response
                      ) -> SetHardwareComponentState.Response:
        hw, host = self._manager.hardware, self._host
        if request.name != hw.name:
            self._log([LogLine('error', f"hardware component with name '{request.name}' does not exist; components: "
                                     f"{hw.name}")])
            response.ok = False
            return response
        with host.lock:
            was_writing, was_connected = hw.writes, hw.available
            result = hw.set_state(int(request.target_state.id), request.target_state.label)
            why = (SCRIPT_EXIT if was_writing and not hw.writes else
                   DISCONNECTED if was_connected and not hw.available else None)
            stopped = why is not None and host.robot.program_running
            if stopped:
                host.robot.stop()
            response.ok = result.ok
            response.state = State(id=hw.state, label=hw.label)
        self._log(LogLine(level, text) for level, text in result.log)
        if stopped:
            self._log([LogLine('info', f'robot: {why}')])
        if result.steps:
            self._changed()
        return response
