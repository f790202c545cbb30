"""ur_msgs, ur_dashboard_msgs, controller_manager_msgs and tf2_msgs must equal upstream.

Type hashes (fields, types, order) are compared with the upstream values of issues 10 and 11; constants
and default values, which the hash does not cover, with the upstream definitions (ur_msgs 2.6.0,
ur_dashboard_msgs 3.8.0, controller_manager_msgs 4.46, tf2_msgs of geometry2 jazzy).
"""
import pytest
from interface_hashes import constants_of, type_hash

UPSTREAM_HASHES = {
    # issue 10
    'ur_msgs/msg/IOStates': 'RIHS01_7a62606d52c4b2aaa3fd3c5bc565cfda9c6fe8c2d69bbc7e3eadccde4cfc2a32',
    'ur_msgs/msg/ToolDataMsg': 'RIHS01_b9fab3f6257c542e53779892ad0e511248ea491ac6327e8a7f0a67cad02090c4',
    'ur_msgs/srv/SetIO': 'RIHS01_5cb0c89ea4479b2947fccdac0f92dd6636c4b7fc3a312f79ec7fb68a1daa6cd5',
    'ur_msgs/srv/SetSpeedSliderFraction': 'RIHS01_04ad37ccb229fa4bce24db36230f09f416a1a637d3b29602907f5675125d402a',
    'ur_msgs/srv/SetPayload': 'RIHS01_75b021dbf765d49d4c238d6f00a210c6b89857e16e9a4b7eddd7d3b546c1f92b',
    'ur_msgs/srv/SetAnalogOutput': 'RIHS01_d9c9e3a1cd35f5d5156d27164b7788d9706c27d308cf6ada484b83d16d5d390e',
    'ur_msgs/srv/GetRobotSoftwareVersion': 'RIHS01_f998c882810c9e7cac8f538dd8c0539b73751c9cf5d7d64bdeea5fe6f70403fd',
    'ur_msgs/action/ToolContact': 'RIHS01_9bbe3e8510ceef3705039d4e873cbfc994dd2283a8c2f2cb6a7aa1c355cd7b91',
    'ur_dashboard_msgs/msg/RobotMode': 'RIHS01_ba3c379b3c995f660b38d03a195dc23ed7571a1bc06ceed2cec38c75ae9bd634',
    'ur_dashboard_msgs/msg/SafetyMode': 'RIHS01_9eb2716e6905f06e4eb60af26712660486e909026aa89c553dd633f1fb22f592',
    'ur_dashboard_msgs/srv/GetRobotMode': 'RIHS01_fccdc8222a9732b7f7cc0e4d81165155d5fc28f20052f1185510a1ff269c7db7',
    'ur_dashboard_msgs/srv/GetSafetyMode': 'RIHS01_e73f0cd9259be725b68a9c1d3e5a416d92ad2e3cf5f49b5f6db77ba204f3537a',
    'ur_dashboard_msgs/srv/GetProgramState': 'RIHS01_292c516872a5576f05cb588f4cbf01a17465051d627aa96e2b4d92914e27da2d',
    'ur_dashboard_msgs/srv/IsProgramRunning': 'RIHS01_627d2ddf4af04b367877c062ed33683eec74644447343ef36d608ffd5485ec99',
    'ur_dashboard_msgs/srv/Load': 'RIHS01_93cb91e732b7a3fd19826528eab6b3f8f3d910df1e7f968f8f14757ff0356524',
    'ur_dashboard_msgs/srv/GetLoadedProgram': 'RIHS01_5bda6d0fee0573a1bbb595ea9b5b3f90c6960925e6bb785358d63e44a53fc669',
    'ur_dashboard_msgs/srv/IsInRemoteControl':
        'RIHS01_33766b9a7536265fad3a6a706a04cc0e7a729b6c8d294dcf7c980e574eb2e086',
    'ur_dashboard_msgs/srv/RawRequest': 'RIHS01_13e3961540d0758b9be89c2087288d2fff104dc6e42b82d18dd7d4b46f805f7c',
    'ur_dashboard_msgs/srv/Popup': 'RIHS01_1fb67ba444b69ca21efc42441e9bd7e36f777cb35bc1c1521641411dd31a832a',
    'ur_dashboard_msgs/srv/AddToLog': 'RIHS01_4d0851a0e27e2c6403f09775a5bbbba434e511d60239a697ac3a893c455d0097',
    'ur_dashboard_msgs/action/SetMode': 'RIHS01_d470705c6f32d8cdacdf7512f1d6dcbd266d8c6e5abfa55ad4494f479f671f2b',
    'tf2_msgs/msg/TFMessage': 'RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087',
    # issue 11
    'controller_manager_msgs/srv/ListControllers':
        'RIHS01_4f8e36bb1fa5afdeba45c2d56ae6a2097b1493a253f961dd6290c085033bd189',
    'controller_manager_msgs/srv/SwitchController':
        'RIHS01_d4ad10aa5da7808bc522d55d4123d8ef79de73d049d165639d7663ac37cc9895',
    'controller_manager_msgs/srv/ListHardwareInterfaces':
        'RIHS01_c3e561a6e8cc7b9d577d8065c783038e51f6950cbe9bed67fb117a3e2e04d8f1',
    'controller_manager_msgs/srv/ListControllerTypes':
        'RIHS01_873e8d2bb81b8b5903ca736d299ba959f929efec4b4a18d17354b8b322822e05',
    # issue 22 (computed from the upstream IDL: ur_dashboard_msgs at the driver commit a16a268,
    # controller_manager_msgs 4.46.0, tf2_msgs of geometry2 jazzy)
    'ur_dashboard_msgs/msg/OperationalMode': 'RIHS01_8aef190ff9d8aa99df44a561cf4e312d83599272bf7979c2af0c53c8d1856a2f',
    'ur_dashboard_msgs/msg/ProgramInformation':
        'RIHS01_27ddd344acddc21cb5ebe4395084e488ffb70c32a6c76eef072326b0340f94f4',
    'ur_dashboard_msgs/msg/ProgramState': 'RIHS01_20e09606e4cba20cbe31680918f25c770a2c46afc44ca91f0cb330559333ed76',
    'ur_dashboard_msgs/msg/SafetyStatus': 'RIHS01_355caf141b54cde62b4c48c0ff8a846183e2a37a1ae383c23fac70fcc7cef95d',
    'ur_dashboard_msgs/msg/UserRole': 'RIHS01_ef2323bcf3c0b5ccae2e88e036f7b55d1249a0a78eb7dd23c5aac1ee01334d40',
    'ur_dashboard_msgs/msg/VersionInformation':
        'RIHS01_910ef49f3108fa14576ff248051d82b7feeebf2f047cafa472efd784d897446f',
    'ur_dashboard_msgs/srv/DownloadProgram': 'RIHS01_2eb188a584fc569c287bdf0799a0fa56611c66d14c968416d9b306aa9db6b137',
    'ur_dashboard_msgs/srv/GenerateFlightReport':
        'RIHS01_281d95be0f701e2798a983b3064341ee93145d2d1bf2607ed4079b5ca8727d3d',
    'ur_dashboard_msgs/srv/GenerateSupportFile':
        'RIHS01_b818b29ac1d8e617d79e7c3b0c1deba2c0e0f94a66fd4c2e3718e0ead7f186f2',
    'ur_dashboard_msgs/srv/GetOperationalMode':
        'RIHS01_06a6bdbb60cb93cfd911c28358f4792ae5b885468041b63e10945b359aa96bae',
    'ur_dashboard_msgs/srv/GetPolyScopeVersion':
        'RIHS01_ce0aaf85c7062fdee29a4aa8081aaba14e4c6436adca0b1ffae196d4e633be2c',
    'ur_dashboard_msgs/srv/GetPrograms': 'RIHS01_2a4e9c6b1a2f8861012ef52e36673106470a5cb732e0f3367a7169c4e2250e3b',
    'ur_dashboard_msgs/srv/GetRobotModel': 'RIHS01_0f0ea4fec0cb4c0f20983173f28ab9fe8b4684714816f7aec1f57b70442ef61b',
    'ur_dashboard_msgs/srv/GetSafetyStatus': 'RIHS01_1b7c685d8c10ae5b26432ab8ec2aca9a81af5e52f4b93c6ca71de1f5ebca8661',
    'ur_dashboard_msgs/srv/GetSerialNumber': 'RIHS01_2cda162b32352c84c7a7a07e68d1378db74f6d73a624843d1b5cb0d1f6447cc3',
    'ur_dashboard_msgs/srv/GetUserRole': 'RIHS01_d55792c1d43380f6898d535c4efb5ece11da009f47114b321e8e8edc6bd83da3',
    'ur_dashboard_msgs/srv/IsProgramSaved': 'RIHS01_4333686bb61da1963f7f8b9a4ba0299263b8ed329c6a161487d19b05ed24d351',
    'ur_dashboard_msgs/srv/SetOperationalMode':
        'RIHS01_75a34fcb9acf5deb450f5be628701673b674daa85fca2ed2fefd81eca4912bbc',
    'ur_dashboard_msgs/srv/SetUserRole': 'RIHS01_a6a1ddde4e6d32a555f0d3f7c17ee4436b4f35583f4474fdd22efff055bd8b4f',
    'ur_dashboard_msgs/srv/UploadProgram': 'RIHS01_a0a1da294e36fdbc6cda01a335696f007541b46bf6b9f683068f8e8d563a7f6a',
    'controller_manager_msgs/msg/HardwareComponentState':
        'RIHS01_8723f76b60e3ea54920065e3e777d93c68b76fc12839ad6a6ca4e0a6439b384c',
    'controller_manager_msgs/srv/ListHardwareComponents':
        'RIHS01_2ff105e609928671af16413362c0fdd089e1dd50c5a49d830db603ba8e4439c8',
    'controller_manager_msgs/srv/SetHardwareComponentState':
        'RIHS01_940b15846ed3e1fb561ab45edf77a992b811fd59c574f45d5205a84a0deb2f65',
    'controller_manager_msgs/srv/LoadController':
        'RIHS01_e37f7596c50c88cf8cb7a10cd376ff7579850cc63b5e787e9c8f11981f9ab4d2',
    'controller_manager_msgs/srv/UnloadController':
        'RIHS01_4055728e84c041348648d7f808c6681562000e3a9ce9fbb42c3350df25773f16',
    'controller_manager_msgs/srv/ConfigureController':
        'RIHS01_b5de498113f4eabc7b932e019ca0498d67304b1ca465fe8a426ea89644865ff9',
    'controller_manager_msgs/srv/CleanupController':
        'RIHS01_0e5e0da84cf97150abbb3a4e2249c67e6f43dba01ed9b7228b4deaab8838ec4b',
    'controller_manager_msgs/srv/ReloadControllerLibraries':
        'RIHS01_485cd0040f8a343a9596155b967363e1bc715f034bbb111f795c73d9d8056a9b',
    'controller_manager_msgs/msg/ControllerManagerActivity':
        'RIHS01_35b7de5d611b6780e89732de325f2f765eacdb8a7adfe5821a27af4a03a7c244',
    'tf2_msgs/msg/TF2Error': 'RIHS01_db2485e7d6a0ec75bf087e058ee45df682acc3a621ca7780503d10aac141809a',
}


@pytest.mark.parametrize('full_name', sorted(UPSTREAM_HASHES))
def test_type_hash_matches_upstream(full_name):
    assert type_hash(full_name) == UPSTREAM_HASHES[full_name]


def _cls(path: str):
    """'ur_msgs.srv.SetIO.Request' -> the generated Python class."""
    module, _, rest = path.partition('.')
    kind, name, *inner = rest.split('.')
    obj = getattr(__import__(f'{module}.{kind}', fromlist=[name]), name)
    for attr in inner:
        obj = getattr(obj, attr)
    return obj


_PINS = {f'PIN_DOUT{i}': i for i in range(8)} | {f'PIN_CONF_OUT{i}': 8 + i for i in range(8)}
_SAFETY_MODES = ['NORMAL', 'REDUCED', 'PROTECTIVE_STOP', 'RECOVERY', 'SAFEGUARD_STOP', 'SYSTEM_EMERGENCY_STOP',
                 'ROBOT_EMERGENCY_STOP', 'VIOLATION', 'FAULT', 'VALIDATE_JOINT_ID', 'UNDEFINED_SAFETY_MODE',
                 'AUTOMATIC_MODE_SAFEGUARD_STOP', 'SYSTEM_THREE_POSITION_ENABLING_STOP']

# Every constant of every upstream type that has constants (all others must have none), as upstream defines them.
UPSTREAM_CONSTANTS = {
    'ur_msgs.srv.SetIO.Request': {
        'PIN_AOUT0': 0, 'PIN_AOUT1': 1, **_PINS, 'PIN_TOOL_DOUT0': 16, 'PIN_TOOL_DOUT1': 17,
        'FUN_SET_DIGITAL_OUT': 1, 'FUN_SET_FLAG': 2, 'FUN_SET_ANALOG_OUT': 3, 'FUN_SET_TOOL_VOLTAGE': 4,
        'STATE_OFF': 0, 'STATE_ON': 1,
        'STATE_TOOL_VOLTAGE_0V': 0, 'STATE_TOOL_VOLTAGE_12V': 12, 'STATE_TOOL_VOLTAGE_24V': 24},
    'ur_msgs.msg.Analog': {'CURRENT': 0, 'VOLTAGE': 1},
    'ur_msgs.msg.ToolDataMsg': {'ANALOG_INPUT_RANGE_CURRENT': 0, 'ANALOG_INPUT_RANGE_VOLTAGE': 1,
                                'TOOL_BOOTLOADER_MODE': 249, 'TOOL_RUNNING_MODE': 253, 'TOOL_IDLE_MODE': 255},
    'ur_msgs.srv.SetForceMode.Request': {'TCP_TO_ORIGIN': 1, 'NO_TRANSFORM': 2, 'TCP_VELOCITY_TO_X_Y': 3},
    'ur_msgs.action.FollowJointTrajectoryUntil.Goal': {'TOOL_CONTACT': 0},
    'ur_msgs.action.FollowJointTrajectoryUntil.Result': {
        'SUCCESSFUL': 0, 'INVALID_GOAL': -1, 'INVALID_JOINTS': -2, 'OLD_HEADER_TIMESTAMP': -3,
        'PATH_TOLERANCE_VIOLATED': -4, 'GOAL_TOLERANCE_VIOLATED': -5, 'TRIGGERED': 0, 'NOT_TRIGGERED': 1},
    'ur_dashboard_msgs.msg.RobotMode': {
        'NO_CONTROLLER': -1, 'DISCONNECTED': 0, 'CONFIRM_SAFETY': 1, 'BOOTING': 2, 'POWER_OFF': 3, 'POWER_ON': 4,
        'IDLE': 5, 'BACKDRIVE': 6, 'RUNNING': 7, 'UPDATING_FIRMWARE': 8},
    'ur_dashboard_msgs.msg.SafetyMode': {name: i + 1 for i, name in enumerate(_SAFETY_MODES)},
    'ur_dashboard_msgs.msg.SafetyStatus': {
        **{name: i + 1 for i, name in enumerate(_SAFETY_MODES)},
        'TP_THREE_POSITION_ENABLING_STOP': 14, 'IMMI_EMERGENCY_STOP': 15, 'IMMI_SAFEGUARD_STOP': 16,
        'PROFISAFE_WAITING_FOR_PARAMETERS': 17, 'PROFISAFE_AUTOMATIC_MODE_SAFEGUARD_STOP': 18,
        'PROFISAFE_SAFEGUARD_STOP': 19, 'PROFISAFE_EMERGENCY_STOP': 20, 'SAFETY_API_SAFEGUARD_STOP': 22,
        'IO_PLANE_STOP': 23},
    'ur_dashboard_msgs.msg.ProgramState': {'STOPPED': 'STOPPED', 'PLAYING': 'PLAYING', 'PAUSED': 'PAUSED'},
    'ur_dashboard_msgs.msg.ProgramInformation': {'PROGRAM_STATE_DRAFT': 'DRAFT', 'PROGRAM_STATE_FINAL': 'FINAL'},
    'ur_dashboard_msgs.msg.OperationalMode': {'MANUAL': 'MANUAL', 'AUTOMATIC': 'AUTOMATIC'},
    'ur_dashboard_msgs.msg.UserRole': {'PROGRAMMER': 'PROGRAMMER', 'OPERATOR': 'OPERATOR', 'NONE': 'NONE',
                                       'LOCKED': 'LOCKED', 'RESTRICTED': 'RESTRICTED'},
    'ur_dashboard_msgs.srv.GenerateFlightReport.Request': {'CONTROLLER': 'controller', 'SOFTWARE': 'software',
                                                           'SYSTEM': 'system'},
    'controller_manager_msgs.srv.SwitchController.Request': {'BEST_EFFORT': 1, 'STRICT': 2, 'AUTO': 3,
                                                             'FORCE_AUTO': 4},
    'tf2_msgs.msg.TF2Error': {'NO_ERROR': 0, 'LOOKUP_ERROR': 1, 'CONNECTIVITY_ERROR': 2, 'EXTRAPOLATION_ERROR': 3,
                              'INVALID_ARGUMENT_ERROR': 4, 'TIMEOUT_ERROR': 5, 'TRANSFORM_ERROR': 6},
}

# Upstream types without constants: a stray constant in our IDL would show here.
WITHOUT_CONSTANTS = [
    'ur_msgs.msg.Digital', 'ur_msgs.msg.IOStates', 'ur_msgs.msg.RobotModeDataMsg', 'ur_msgs.srv.SetPayload.Request',
    'ur_msgs.action.ToolContact.Goal', 'ur_msgs.action.ToolContact.Result', 'ur_msgs.action.SendScript.Goal',
    'ur_dashboard_msgs.msg.VersionInformation', 'ur_dashboard_msgs.action.SetMode.Goal',
    'controller_manager_msgs.msg.ControllerState', 'controller_manager_msgs.msg.HardwareInterface',
    'tf2_msgs.msg.TFMessage',
]


@pytest.mark.parametrize('path', sorted(UPSTREAM_CONSTANTS))
def test_constants_equal_upstream(path):
    assert constants_of(_cls(path)) == UPSTREAM_CONSTANTS[path]


@pytest.mark.parametrize('path', WITHOUT_CONSTANTS)
def test_no_constants_where_upstream_has_none(path):
    assert constants_of(_cls(path)) == {}


def test_default_values_equal_upstream():
    from ur_dashboard_msgs.srv import GenerateFlightReport, GenerateSupportFile
    from ur_msgs.action import SendScript
    from ur_msgs.srv import SetForceMode

    force = SetForceMode.Request()
    assert force.type == SetForceMode.Request.NO_TRANSFORM == 2
    assert [force.selection_vector_x, force.selection_vector_y, force.selection_vector_z, force.selection_vector_rx,
            force.selection_vector_ry, force.selection_vector_rz] == [False] * 6
    assert list(force.deviation_limits) == pytest.approx([0.01] * 6)
    assert (force.damping_factor, force.gain_scaling) == (pytest.approx(0.025), pytest.approx(0.5))
    script = SendScript.Goal()
    assert (script.program, script.script_name, script.fail_on_warnings) == ('', '', True)
    assert GenerateFlightReport.Request().report_type == 'SYSTEM'
    assert GenerateSupportFile.Request().dir_path == '.'


def test_set_payload_is_the_2_6_0_layout():
    """2.6.0 appended six inertia terms and a transition time to mass and centre of gravity."""
    from ur_msgs.srv import SetPayload

    assert SetPayload.Request.get_fields_and_field_types() == {
        'mass': 'float', 'center_of_gravity': 'geometry_msgs/Vector3', 'ixx': 'double', 'iyy': 'double',
        'izz': 'double', 'ixy': 'double', 'ixz': 'double', 'iyz': 'double',
        'transition_time': 'builtin_interfaces/Duration'}
