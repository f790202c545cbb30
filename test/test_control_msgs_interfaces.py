"""control_msgs must be wire-compatible with upstream: the generated type hashes are compared on the wire."""
import pytest
from interface_hashes import type_hash

# Upstream control_msgs 5.x (Jazzy) values, given in the foundation issue.
UPSTREAM_HASHES = {
    ('action', 'FollowJointTrajectory'): 'RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6',
    ('msg', 'JointTolerance'): 'RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648',
}


@pytest.mark.parametrize(('kind', 'name'), sorted(UPSTREAM_HASHES))
def test_type_hash_matches_upstream(kind, name):
    assert type_hash(f'control_msgs/{kind}/{name}') == UPSTREAM_HASHES[(kind, name)]


def test_result_codes_and_field_order():
    from control_msgs.action import FollowJointTrajectory

    result = FollowJointTrajectory.Result
    codes = {k: getattr(result, k) for k in ('SUCCESSFUL', 'INVALID_GOAL', 'INVALID_JOINTS', 'OLD_HEADER_TIMESTAMP',
                                             'PATH_TOLERANCE_VIOLATED', 'GOAL_TOLERANCE_VIOLATED')}
    assert codes == {'SUCCESSFUL': 0, 'INVALID_GOAL': -1, 'INVALID_JOINTS': -2, 'OLD_HEADER_TIMESTAMP': -3,
                     'PATH_TOLERANCE_VIOLATED': -4, 'GOAL_TOLERANCE_VIOLATED': -5}
    assert list(result.get_fields_and_field_types()) == ['error_code', 'error_string']
    assert list(FollowJointTrajectory.Goal.get_fields_and_field_types()) == [
        'trajectory', 'multi_dof_trajectory', 'path_tolerance', 'component_path_tolerance', 'goal_tolerance',
        'component_goal_tolerance', 'goal_time_tolerance']


def test_other_interfaces_fields():
    from control_msgs.msg import JointComponentTolerance, JointTrajectoryControllerState, SpeedScalingFactor
    from control_msgs.srv import QueryTrajectoryState

    assert list(JointTrajectoryControllerState.get_fields_and_field_types())[-1] == 'speed_scaling_factor'
    assert SpeedScalingFactor.get_fields_and_field_types() == {'factor': 'double'}
    assert (JointComponentTolerance.X_AXIS, JointComponentTolerance.ROTATION) == (1, 5)
    assert list(QueryTrajectoryState.Response.get_fields_and_field_types()) == [
        'success', 'message', 'name', 'position', 'velocity', 'acceleration']
