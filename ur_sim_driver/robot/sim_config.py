"""Validated configuration of the `ur_sim` node, built from plain parameter values (no rclpy)."""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ur_sim_driver.description.params import UR_TYPES
from ur_sim_driver.description.scene import scene_file
from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.dispenser import DispenserParams, dispenser_params
from ur_sim_driver.robot.payload import NO_PAYLOAD, Payload, make_payload
from ur_sim_driver.robot.safety import DEFAULT_CONTACT_FORCE, DEFAULT_FORCE_WINDOW
from ur_sim_driver.robot.software import SoftwareVersion, default_version, parse_version

TOOLS = ('none', 'dispenser')
DEFAULT_JOINTS = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
                  'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint')


@dataclass(frozen=True)
class JointConstraint:
    """Default JTC tolerances of one joint: `trajectory` (path) and `goal` position [rad]."""

    trajectory: float = 0.2
    goal: float = 0.1


@dataclass(frozen=True)
class SimConfig:
    """Everything `ur_sim` needs to start. Defaults are the UR driver's."""

    ur_type: str = 'ur5e'  # the type the driver is configured for: the description, the hardware component's name
    # The robot ur_sim simulates, as URSim's model is chosen ('': the same as ur_type). Physics, dashboard, payload
    # rating and software version are the robot's; the driver checks the two agree (verify_robot_model).
    simulated_ur_type: str = ''
    verify_robot_model: bool = True  # ur.urdf.xacro's default
    # Joint efforts (/joint_states, the effort state interfaces) as the motor currents [A], as the driver at a16a268
    # reports them; false: the torques less gravity [N m] (RTDE actual_current_as_torque, 5.23.0 / 10.11.0 on), as
    # the hardware parameter of the driver's later releases (robot/motor_currents.py).
    use_currents_as_efforts: bool = True
    tf_prefix: str = ''
    namespace: str = ''
    joints: tuple[str, ...] = DEFAULT_JOINTS
    controller_name: str = 'scaled_joint_trajectory_controller'
    initial_positions: tuple[float, ...] = (0.0, -1.57, 0.0, -1.57, 0.0, 0.0)
    action_monitor_rate: float = 20.0
    allow_partial_joints_goal: bool = False
    allow_nonzero_velocity_at_trajectory_end: bool = False
    strict_limit_checks: bool = False
    start_powered_off: bool = False
    programs: tuple[str, ...] = ('wait_program.urp',)
    protective_stop_force: float = DEFAULT_CONTACT_FORCE
    protective_stop_window: float = DEFAULT_FORCE_WINDOW  # [s] the safety system's mean of the contact force
    update_rate: float = 0.0
    physics_substeps: int = 0
    # The trajectory controllers' own factor at start (ros2_controllers' speed_scaling.initial_scaling_factor, >= 0).
    initial_scaling_factor: float = 1.0
    # urscript.allow_remote_sockets: a program's socket_open may reach hosts other than loopback addresses.
    allow_remote_sockets: bool = False
    real_time_factor: float = 1.0
    # In step with a client: the loop steps only while the simulated time is at most pace_lag [s] past the time the
    # client last published on pace_topic (rosgraph_msgs/Clock), at real time's pace before its first message; ''
    # runs free (ros/pace_gate.py).
    pace_topic: str = ''
    pace_lag: float = 0.02
    thread_priority: int = 50  # SCHED_FIFO priority of the real-time loop, as ros2_control_node's; 0: normal
    # The robot's dashboard server on TCP (ports/dashboard_port.py): 29999 as on a UR; 0 lets the system choose.
    dashboard_server_host: str = '127.0.0.1'
    dashboard_server_port: int = 29999
    rtde_host: str = '127.0.0.1'  # RTDE (ports/rtde_port.py): 30004 as on a UR; 0 lets the system choose
    rtde_port: int = 30004
    # The primary and secondary interfaces (ports/primary_port.py): 30001 and 30002 as on a UR.
    primary_host: str = '127.0.0.1'
    primary_port: int = 30001
    secondary_host: str = '127.0.0.1'
    secondary_port: int = 30002
    realtime_host: str = '127.0.0.1'  # the real-time interface: 30003 as on a UR
    realtime_port: int = 30003
    interpreter_host: str = '127.0.0.1'  # the interpreter socket (ports/interpreter_port.py): 30020 as on a UR
    interpreter_port: int = 30020
    tool: str = 'none'
    scene: str = 'empty'
    part_scan_seed: int = 0  # seeds the part scanners' noise (a scene with scanners): the same seed, the same scans
    base_pose: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    viewer: bool = False
    stopped_velocity_tolerance: float = 0.2
    goal_time: float = 0.0
    constraints: tuple[JointConstraint, ...] = (JointConstraint(),) * 6
    publish_frequency: float = 20.0  # [Hz] of simulated time: robot_state_publisher's /tf
    dispenser: DispenserParams = DispenserParams()  # the glue dispenser's model (tool: dispenser only)
    # What is physically mounted at the flange besides the tool (set_payload only changes the controller's belief).
    mounted_payload: Payload = NO_PAYLOAD
    software_version: SoftwareVersion | None = None  # the controller's software; None: the type's default
    # The driver's launch arguments that change what a client sees (ur_control.launch.py, same names and defaults).
    initial_joint_controller: str = 'scaled_joint_trajectory_controller'
    activate_joint_controller: bool = True
    launch_dashboard_client: bool = True
    headless_mode: bool = False  # the driver sends its program itself; resend_robot_program works only then
    use_tool_communication: bool = False  # the tool's RS-485 bridge: not simulated (true is refused)
    # The controller manager's hardware_components_initial_state.{unconfigured, inactive} (lists of component names),
    # resolved for ur_sim's one component (named after ur_type): 'unconfigured', 'inactive' or 'active'.
    hardware_components_initial_state: str = 'active'

    def __post_init__(self) -> None:
        if not self.simulated_ur_type:
            object.__setattr__(self, 'simulated_ur_type', self.ur_type)
        if self.software_version is None:  # resolved once: every reader sees the version the robot runs
            object.__setattr__(self, 'software_version', default_version(self.simulated_ur_type))

    def prefixed(self, name: str) -> str:
        """`name` under the configured namespace, e.g. '/ur10/joint_states'."""
        ns = self.namespace.strip('/')
        return f'/{ns}/{name}' if ns else f'/{name}'


def _choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise ConfigError(f"parameter '{name}' = {value!r} is invalid; valid choices: {', '.join(choices)}")
    return value


def _pace_topic(value: Any) -> str:
    """'' (no pacing) or a topic name."""
    if not isinstance(value, str) or any(c.isspace() for c in value):
        raise ConfigError(f"parameter 'pace_topic' = {value!r} must be '' (run free) or a topic name, e.g. "
                          "'/ur_sim/pace'")
    return value


def _scene(value: Any) -> str:
    """'empty', a scene in config/scenes or the path of a scene file (checked: the name must resolve)."""
    if value == 'empty':
        return value
    try:
        scene_file(str(value))
    except ConfigError as exc:
        raise ConfigError(f"parameter 'scene': {exc}") from None
    return str(value)


def _number(name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"parameter '{name}' = {value!r} is not a number") from None
    bad_lo = x <= lo if lo_open else x < lo
    if not math.isfinite(x) or bad_lo or x > hi:
        bracket = '(' if lo_open else '['
        raise ConfigError(f"parameter '{name}' = {value!r} is outside the allowed range {bracket}{lo}, {hi}]")
    return x


def _host(name: str, value: Any) -> str:
    if not isinstance(value, str) or not value.strip() or any(c.isspace() for c in value):
        raise ConfigError(f"parameter '{name}' = {value!r} must be a host name or address, e.g. '127.0.0.1' "
                          "(this machine only) or '0.0.0.0' (every interface)")
    return value


def _integer(name: str, value: Any, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise ConfigError(f"parameter '{name}' = {value!r} must be an integer in [{lo}, {hi}]")
    return value


def sim_config_from_params(params: Mapping[str, Any]) -> SimConfig:
    """Validate raw parameter values into a SimConfig.

    Args:
        params: flat mapping as ROS parameters give it, e.g. {'ur_type': 'ur10',
            'constraints.goal_time': 0.1, 'constraints.elbow_joint.goal': 0.05}. Missing keys take defaults.

    Raises:
        ConfigError: naming the parameter, the value and the allowed range or choices.
    """
    d = SimConfig()
    get = params.get
    joints = tuple(get('joints', d.joints))
    if len(joints) != 6 or len(set(joints)) != 6 or not all(isinstance(j, str) and j for j in joints):
        raise ConfigError(f"parameter 'joints' = {list(joints)!r} must be 6 distinct non-empty joint names")
    initial = tuple(float(x) for x in get('initial_positions', d.initial_positions))
    if len(initial) != 6 or not all(math.isfinite(x) for x in initial):
        raise ConfigError(f"parameter 'initial_positions' = {list(initial)!r} must be 6 finite numbers [rad]")
    substeps = get('physics_substeps', d.physics_substeps)
    if isinstance(substeps, bool) or not isinstance(substeps, int) or not 0 <= substeps <= 100:
        raise ConfigError(f"parameter 'physics_substeps' = {substeps!r} must be a whole number in [0, 100] "
                          '(0: automatic, physics step <= 2 ms)')
    constraints = []
    prefix = str(get('tf_prefix', d.tf_prefix))
    for j in joints:
        # Keys may name the joint with its tf_prefix (as ur_controllers.yaml does) or without.
        key = f'constraints.{prefix}{j}' if f'constraints.{prefix}{j}.goal' in params or \
            f'constraints.{prefix}{j}.trajectory' in params else f'constraints.{j}'
        constraints.append(JointConstraint(
            trajectory=_number(f'{key}.trajectory', get(f'{key}.trajectory', 0.2), 0.0, 10.0),
            goal=_number(f'{key}.goal', get(f'{key}.goal', 0.1), 0.0, 10.0),
        ))
    base_pose = tuple(float(x) for x in get('base_pose', d.base_pose))
    if len(base_pose) != 6 or not all(math.isfinite(x) for x in base_pose):
        raise ConfigError(f"parameter 'base_pose' = {list(base_pose)!r} must be 6 finite numbers "
                          '[x, y, z [m], roll, pitch, yaw [rad]]')
    update_rate = _number('update_rate', get('update_rate', d.update_rate), 0.0, 5000.0)
    if 0.0 < update_rate < 10.0:
        raise ConfigError(f"parameter 'update_rate' = {update_rate} is outside the allowed range: 0 (type default) "
                          'or [10, 5000] Hz')
    ur_type = _choice('ur_type', get('ur_type', d.ur_type), UR_TYPES)
    robot = get('simulated_ur_type', '') or ur_type
    robot = _choice('simulated_ur_type', robot, UR_TYPES)
    return SimConfig(
        ur_type=ur_type,
        simulated_ur_type=robot,
        verify_robot_model=bool(get('verify_robot_model', d.verify_robot_model)),
        use_currents_as_efforts=bool(get('use_currents_as_efforts', d.use_currents_as_efforts)),
        software_version=parse_version(str(get('software_version', '')), robot),
        tf_prefix=str(get('tf_prefix', d.tf_prefix)),
        namespace=str(get('namespace', d.namespace)),
        joints=joints,
        controller_name=_controller_name(get('controller_name', d.controller_name)),
        initial_positions=initial,
        action_monitor_rate=_number('action_monitor_rate', get('action_monitor_rate', d.action_monitor_rate),
                                    0.0, 1000.0, lo_open=True),
        allow_partial_joints_goal=bool(get('allow_partial_joints_goal', d.allow_partial_joints_goal)),
        allow_nonzero_velocity_at_trajectory_end=bool(
            get('allow_nonzero_velocity_at_trajectory_end', d.allow_nonzero_velocity_at_trajectory_end)),
        strict_limit_checks=bool(get('strict_limit_checks', d.strict_limit_checks)),
        start_powered_off=bool(get('start_powered_off', d.start_powered_off)),
        programs=_programs(get('programs', d.programs)),
        protective_stop_force=_number('protective_stop_force', get('protective_stop_force',
                                                                   d.protective_stop_force), 0.0, 1e4,
                                      lo_open=True),
        protective_stop_window=_number('protective_stop_window', get('protective_stop_window',
                                                                     d.protective_stop_window), 0.0, 1.0),
        update_rate=update_rate,
        physics_substeps=substeps,
        allow_remote_sockets=bool(get('urscript.allow_remote_sockets', d.allow_remote_sockets)),
        initial_scaling_factor=_number('speed_scaling.initial_scaling_factor',
                                       get('speed_scaling.initial_scaling_factor', d.initial_scaling_factor),
                                       0.0, math.inf),
        real_time_factor=_number('real_time_factor', get('real_time_factor', d.real_time_factor), 0.0, 100.0),
        pace_topic=_pace_topic(get('pace_topic', d.pace_topic)),
        pace_lag=_number('pace_lag', get('pace_lag', d.pace_lag), 0.0, 10.0, lo_open=True),
        thread_priority=_integer('thread_priority', get('thread_priority', d.thread_priority), 0, 99),
        dashboard_server_host=_host('dashboard_server.host', get('dashboard_server.host', d.dashboard_server_host)),
        dashboard_server_port=_integer('dashboard_server.port', get('dashboard_server.port', d.dashboard_server_port),
                                       0, 65535),
        rtde_host=_host('rtde.host', get('rtde.host', d.rtde_host)),
        rtde_port=_integer('rtde.port', get('rtde.port', d.rtde_port), 0, 65535),
        primary_host=_host('primary.host', get('primary.host', d.primary_host)),
        primary_port=_integer('primary.port', get('primary.port', d.primary_port), 0, 65535),
        secondary_host=_host('secondary.host', get('secondary.host', d.secondary_host)),
        secondary_port=_integer('secondary.port', get('secondary.port', d.secondary_port), 0, 65535),
        realtime_host=_host('realtime.host', get('realtime.host', d.realtime_host)),
        realtime_port=_integer('realtime.port', get('realtime.port', d.realtime_port), 0, 65535),
        interpreter_host=_host('interpreter.host', get('interpreter.host', d.interpreter_host)),
        interpreter_port=_integer('interpreter.port', get('interpreter.port', d.interpreter_port), 0, 65535),
        tool=_choice('tool', get('tool', d.tool), TOOLS),
        scene=_scene(get('scene', d.scene)),
        part_scan_seed=_integer('part_scan_seed', get('part_scan_seed', d.part_scan_seed), 0, 2**31 - 1),
        base_pose=base_pose,
        viewer=bool(get('viewer', d.viewer)),
        stopped_velocity_tolerance=_number('constraints.stopped_velocity_tolerance',
                                           get('constraints.stopped_velocity_tolerance', 0.2), 0.0, 10.0),
        goal_time=_number('constraints.goal_time', get('constraints.goal_time', 0.0), 0.0, 3600.0),
        constraints=tuple(constraints),
        publish_frequency=_number('publish_frequency', get('publish_frequency', d.publish_frequency), 0.0, 1000.0,
                                  lo_open=True),
        dispenser=dispenser_params(params),
        mounted_payload=_mounted_payload(params),
        initial_joint_controller=_ros_name('initial_joint_controller',
                                           get('initial_joint_controller', d.initial_joint_controller)),
        activate_joint_controller=bool(get('activate_joint_controller', d.activate_joint_controller)),
        launch_dashboard_client=bool(get('launch_dashboard_client', d.launch_dashboard_client)),
        headless_mode=bool(get('headless_mode', d.headless_mode)),
        use_tool_communication=_tool_communication(get('use_tool_communication', d.use_tool_communication)),
        hardware_components_initial_state=_initial_hardware_state(params, ur_type),
    )


def _mounted_payload(params: Mapping[str, Any]) -> Payload:
    """`mounted_payload.mass` [kg], `.cog` (3,) [m] in tool0, `.inertia` (6,) ixx iyy izz ixy ixz iyz [kg m^2]."""
    get = params.get
    mass = get('mounted_payload.mass', 0.0)
    cog = get('mounted_payload.cog', [0.0, 0.0, 0.0])
    inertia = get('mounted_payload.inertia', [0.0] * 6)
    try:
        return make_payload(mass, list(cog), list(inertia))
    except (ConfigError, TypeError, ValueError) as exc:
        raise ConfigError(f"parameters 'mounted_payload.*' (mass {mass!r}, cog {cog!r}, inertia {inertia!r}): "
                          f'{exc}') from None


def _initial_hardware_state(params: Mapping[str, Any], component: str) -> str:
    """The hardware component's state at start from the controller manager's two lists; the component is named
    after ur_type, as the driver's description names it."""
    state = 'active'
    for label in ('unconfigured', 'inactive'):
        key = f'hardware_components_initial_state.{label}'
        value = params.get(key, [])
        names = [value] if isinstance(value, str) else list(value)
        for name in names:
            if name != component:
                raise ConfigError(f"parameter '{key}' = {names!r} names an unknown hardware component {name!r}; "
                                  f'valid: {component} (the component is named after ur_type)')
        if names and state == 'active':
            state = label
    return state


def _tool_communication(value: Any) -> bool:
    if bool(value):
        raise ConfigError(f"parameter 'use_tool_communication' = {value!r}: the tool's serial (RS-485) bridge is not "
                          'simulated; valid: false')
    return False


def _programs(value: Any) -> tuple[str, ...]:
    # Program files the simulated robot holds besides external_control.urp (the dashboard can load them).
    names = (value,) if isinstance(value, str) else tuple(value)
    for name in names:
        if not isinstance(name, str) or not name.endswith('.urp') or '/' in name or name == '.urp':
            raise ConfigError(f"parameter 'programs' = {list(names)!r} must be program file names ending in "
                              f"'.urp' without a directory; {name!r} is not")
    return names


def _controller_name(value: Any) -> str:
    return _ros_name('controller_name', value)


def _ros_name(parameter: str, value: Any) -> str:
    name = str(value)
    if not name or not all(c.isalnum() or c == '_' for c in name) or name[0].isdigit():
        raise ConfigError(f"parameter '{parameter}' = {value!r} is not a valid ROS name "
                          '(letters, digits and underscores, not starting with a digit)')
    return name


# Parameter names ur_sim reads: the configuration's fields, groups read as <group>.<name>, and rclpy's own.
_PORTS = ('dashboard_server', 'rtde', 'primary', 'secondary', 'realtime', 'interpreter')
_GROUPS = ('constraints', 'speed_scaling', 'urscript', *_PORTS)
_GROUPED = {f'{g}_{n}' for g in _PORTS for n in ('host', 'port')}
_IN_GROUPS = {'initial_scaling_factor', 'allow_remote_sockets'}  # speed_scaling.*, urscript.*
_KNOWN = (set(SimConfig.__dataclass_fields__) - _IN_GROUPS - _GROUPED) | set(_GROUPS) | {
    'use_sim_time', 'start_type_description_service'}
PARAMETER_NAMES = ', '.join(sorted(f'{n}.*' if n in _GROUPS else n for n in _KNOWN))


def unknown_parameters(names) -> list[str]:
    """The names among `names` (flat, e.g. 'dashboard_server.port') that ur_sim does not read."""
    return [n for n in names if n.split('.')[0] not in _KNOWN]
