"""Reading serialized JointTrajectory bytes (as a raw subscription gets them) into CommandArrays."""
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway.cdr import parse_joint_trajectory
from ur_sim_driver.motion.command_arrays import from_points


def message(points, names=('a', 'bb', 'ccc'), stamp=(3, 250_000_000), frame='base'):
    msg = JointTrajectory(joint_names=list(names), points=points)
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    return msg


def point(t, q, v=(), a=(), e=()):
    p = JointTrajectoryPoint(positions=list(q), velocities=list(v), accelerations=list(a), effort=list(e))
    p.time_from_start.sec, p.time_from_start.nanosec = int(t), int(round((t % 1) * 1e9))
    return p


@pytest.mark.parametrize('frame', ['', 'b', 'base', 'base_link'])  # every alignment of what follows
def test_parse_equals_the_message_contents(frame):
    pts = [point(0.5, [1, 2, 3], [0.1, 0.2, 0.3]), point(1.0, [4, 5, 6]), point(2.25, [7, 8, 9], [0, 0, 0], [1, 1, 1])]
    msg = message(pts, frame=frame)
    parsed = parse_joint_trajectory(serialize_message(msg))
    expected = from_points(msg.joint_names, 3.25, msg.points)
    assert parsed.joint_names == ('a', 'bb', 'ccc') and parsed.header_stamp == pytest.approx(3.25)
    assert np.array_equal(parsed.sizes, expected.sizes)
    assert np.allclose(parsed.times, [0.5, 1.0, 2.25])
    for got, want in zip(parsed.values, expected.values):
        assert np.array_equal(got, want)


def test_ragged_points_keep_their_sizes():
    msg = message([point(1.0, [1, 2]), point(2.0, [1, 2, 3], [1.0], [], [5, 5, 5, 5])])
    parsed = parse_joint_trajectory(serialize_message(msg))
    assert parsed.sizes.tolist() == [[2, 0, 0, 0], [3, 1, 0, 4]]
    assert parsed.point_values(0, 1).tolist() == [1, 2, 3]
    assert parsed.point_values(3, 1).tolist() == [5, 5, 5, 5]


def test_empty_message():
    parsed = parse_joint_trajectory(serialize_message(JointTrajectory()))
    assert parsed.count == 0 and parsed.joint_names == ()


def test_truncated_bytes_raise_a_clear_error():
    data = serialize_message(message([point(1.0, [1, 2, 3])] * 3))
    with pytest.raises(TrajectoryError, match='malformed JointTrajectory'):
        parse_joint_trajectory(data[:len(data) // 2])
    with pytest.raises(TrajectoryError, match='malformed JointTrajectory'):
        parse_joint_trajectory(b'\x07\x07')
