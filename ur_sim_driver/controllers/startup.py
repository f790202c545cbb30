"""Which controllers the driver's launch file starts active (``ur_control.launch.py`` at the pinned commit).

The launch file spawns broadcasters and status controllers active, and the joint controllers inactive except
``initial_joint_controller``, which it activates when ``activate_joint_controller`` is true (it removes that name
from the inactive list, so a name not in the list fails the launch). ur_sim takes the same two parameters; its
scaled trajectory controller is named by ``controller_name``, so the default ``scaled_joint_trajectory_controller``
means that controller whatever its name.
"""
from __future__ import annotations

from collections.abc import Iterable

from ur_sim_driver.controllers.base import Component
from ur_sim_driver.controllers.ur_hardware import EFFORT_TOO_OLD, robot_model_refusal, torque_efforts_refusal
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.sim_config import SimConfig
from ur_sim_driver.robot.software import TORQUE_CONTROL, supports

SCALED = 'scaled_joint_trajectory_controller'
EFFORT = 'forward_effort_controller'
# The launch file's inactive list.
JOINT_CONTROLLERS = (SCALED, 'joint_trajectory_controller', 'forward_velocity_controller',
                     'forward_position_controller', EFFORT, 'force_mode_controller',
                     'passthrough_trajectory_controller', 'freedrive_mode_controller', 'tool_contact_controller')


def joint_controllers(cfg: SimConfig) -> tuple[str, ...]:
    """The names of the controllers the launch file spawns inactive, as ur_sim names them."""
    names = [cfg.controller_name if n == SCALED else n for n in JOINT_CONTROLLERS]
    return tuple(dict.fromkeys(names))


def initial_joint_controller(cfg: SimConfig) -> str | None:
    """The joint controller active after start, or None (``activate_joint_controller`` false).

    Raises:
        ConfigError: ``initial_joint_controller`` names no controller of the list, naming the valid ones.
    """
    if not cfg.activate_joint_controller:
        return None
    name = cfg.controller_name if cfg.initial_joint_controller == SCALED else cfg.initial_joint_controller
    choices = joint_controllers(cfg)
    if name not in choices:
        raise ConfigError(f"parameter 'initial_joint_controller' = {cfg.initial_joint_controller!r} is not a joint "
                          f"controller of ur_sim; valid choices: {', '.join(choices)}")
    if name == EFFORT and not supports(cfg.software_version, TORQUE_CONTROL):
        # The driver's spawner would fail on the hardware's refusal; ur_sim says so at start.
        raise ConfigError(f"parameter 'initial_joint_controller' = {name!r} cannot be activated: {EFFORT_TOO_OLD}; "
                          f"valid choices: {', '.join(c for c in choices if c != EFFORT)}")
    return name


def configure_refusal(cfg: SimConfig) -> str | None:
    """The hardware component's refusal to configure, as its ``on_configure``: the robot is not the configured type
    (with ``verify_robot_model``), or it has no torques to report as efforts (``use_currents_as_efforts`` false on
    a software older than 5.23.0 / 10.11.0); None when it configures."""
    if cfg.verify_robot_model:
        reason = robot_model_refusal(cfg.ur_type, cfg.simulated_ur_type, cfg.software_version)
        if reason is not None:
            return reason
    return None if cfg.use_currents_as_efforts else torque_efforts_refusal(cfg.software_version)


def check_start(cfg: SimConfig) -> None:
    """Raise as ros2_control_node ends at start when its hardware component cannot reach its initial state
    (``hardware_components_initial_state.shutdown_on_initial_state_failure`` is true by default): configuring it
    fails (:func:`configure_refusal`). A component left unconfigured starts, and refuses later.

    Raises:
        ConfigError: the driver's message, then the controller manager's, and the parameters behind it.
    """
    state = cfg.hardware_components_initial_state
    reason = configure_refusal(cfg) if state != 'unconfigured' else None
    if reason is None:
        return
    if cfg.use_currents_as_efforts or torque_efforts_refusal(cfg.software_version) is None:
        cause = (f"parameters 'ur_type' = {cfg.ur_type!r}, 'simulated_ur_type' = {cfg.simulated_ur_type!r}; "
                 "'verify_robot_model' = false runs them anyway")
    else:
        cause = (f"parameters 'use_currents_as_efforts' = false, 'software_version' = "
                 f"'{cfg.software_version}'; valid choices: use_currents_as_efforts true, or a software_version of "
                 '5.23.0 / 10.11.0 or newer')
    raise ConfigError(f'{reason} Failed to set the initial state of the component : {cfg.ur_type} to {state} '
                      f'({cause})')


# The controller_stopper's "consistent_controllers" (the launch file's list): these keep running while the robot
# cannot move; every other active controller is deactivated then and activated again afterwards.
CONSISTENT = ('io_and_status_controller', 'force_torque_sensor_broadcaster', 'joint_state_broadcaster',
              'speed_scaling_state_broadcaster', 'tcp_pose_broadcaster', 'ur_configuration_controller',
              'gravity_update_controller')


def set_start_states(cfg: SimConfig, initial: str | None, components: Iterable[Component]) -> str | None:
    """Set each component's ``initially_active`` as the launch file's spawners leave it: the joint controllers
    inactive but `initial`; with a hardware component that does not start active, no controller at all (the
    spawner's one switch is refused: state interfaces unavailable, or commands the component cannot take). Returns
    the warning to log in that case, else None."""
    joint = joint_controllers(cfg)
    hardware = cfg.hardware_components_initial_state
    for component in components:
        if component.name in joint:
            component.initially_active = component.name == initial
        if hardware != 'active' and component.is_controller:
            component.initially_active = False
    if hardware == 'active':
        return None
    return (f"hardware component '{cfg.ur_type}' starts {hardware} (hardware_components_initial_state): no "
            'controller is activated; activate it with set_hardware_component_state, then switch the controllers on')
