"""The strided reader of serialized JointTrajectory bytes: the same arrays as the general reader, for any message."""
import numpy as np
import pytest
from rclpy.serialization import serialize_message
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.gateway import trajectory_cdr
from ur_sim_driver.gateway.cdr import parse_joint_trajectory
from ur_sim_driver.gateway.trajectory_cdr import read_joint_trajectory


def message(points, names=('a', 'bb', 'ccc'), frame='base', stamp=(3, 250_000_000)) -> bytes:
    msg = JointTrajectory(joint_names=list(names), points=points)
    msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
    msg.header.frame_id = frame
    return serialize_message(msg)


def point(t, q=(), v=(), a=(), e=()):
    p = JointTrajectoryPoint(positions=list(q), velocities=list(v), accelerations=list(a), effort=list(e))
    p.time_from_start.sec, p.time_from_start.nanosec = int(t), int(round((t % 1) * 1e9))
    return p


def assert_same(got, want):
    assert got.joint_names == want.joint_names and got.header_stamp == want.header_stamp
    assert np.array_equal(got.times, want.times) and np.array_equal(got.sizes, want.sizes)
    for x, y in zip(got.values, want.values):
        assert x.dtype == y.dtype == np.float64 and np.array_equal(x, y)


def regular(count, shape, rng):
    return [point(0.01 * (k + 1), *(rng.normal(size=m) for m in shape)) for k in range(count)]


@pytest.mark.parametrize('frame', ['', 'b', 'base', 'base_link'])  # every alignment of the points
@pytest.mark.parametrize('shape', [(3, 3, 0, 0), (3, 0, 0, 0), (3, 3, 3, 3), (1, 0, 0, 0), (1, 1, 1, 0), (0, 0, 0, 0),
                                   (2, 1, 0, 5)])
def test_regular_points_are_read_by_stride_and_equal_the_general_reader(frame, shape):
    data = message(regular(50, shape, np.random.default_rng(1)), frame=frame)
    strided = trajectory_cdr._read_regular(data)
    assert strided is not None
    assert_same(strided, parse_joint_trajectory(data))
    assert_same(read_joint_trajectory(data), parse_joint_trajectory(data))


def test_a_first_point_of_another_shape_is_still_read_by_stride():
    rng = np.random.default_rng(2)
    points = [point(0.0, [1.0, 2.0, 3.0])] + regular(20, (3, 3, 0, 0), rng)
    data = message(points)
    assert trajectory_cdr._read_regular(data) is not None
    assert_same(read_joint_trajectory(data), parse_joint_trajectory(data))


@pytest.mark.parametrize('seed', range(40))
def test_random_messages_read_as_the_general_reader_does(seed):
    rng = np.random.default_rng(seed)
    joints = int(rng.integers(0, 7))
    shape = [int(rng.choice([0, joints, rng.integers(0, 4)])) for _ in range(4)]
    points = []
    for _ in range(int(rng.integers(0, 15))):
        sizes = shape if rng.random() > 0.15 else [int(rng.integers(0, 4)) for _ in range(4)]
        points.append(point(float(rng.uniform(0, 50)), *(rng.normal(size=m) for m in sizes)))
    data = message(points, names=[f'j{i}' * int(rng.integers(1, 4)) for i in range(joints)],
                   frame='x' * int(rng.integers(0, 7)), stamp=(int(rng.integers(0, 100)), int(rng.integers(0, 10**9))))
    assert_same(read_joint_trajectory(data), parse_joint_trajectory(data))


def test_a_ragged_point_after_the_second_leaves_it_to_the_general_reader():
    rng = np.random.default_rng(3)
    points = regular(10, (3, 3, 0, 0), rng)
    points[7] = point(5.0, [1.0, 2.0, 3.0])
    data = message(points)
    assert trajectory_cdr._read_regular(data) is None
    assert_same(read_joint_trajectory(data), parse_joint_trajectory(data))


def test_malformed_bytes_raise_the_general_readers_error():
    data = message(regular(10, (3, 3, 0, 0), np.random.default_rng(4)))
    for bad in (data[:len(data) // 2], data[:200], b'\x07\x07'):
        with pytest.raises(TrajectoryError, match='malformed JointTrajectory'):
            read_joint_trajectory(bad)


def test_every_truncation_is_read_as_the_general_reader_reads_it():
    data = message(regular(6, (2, 2, 0, 0), np.random.default_rng(5)))
    for end in range(len(data) + 1):
        try:
            want = parse_joint_trajectory(data[:end])
        except TrajectoryError as exc:
            with pytest.raises(TrajectoryError) as got:
                read_joint_trajectory(data[:end])
            assert str(got.value) == str(exc)
        else:
            assert_same(read_joint_trajectory(data[:end]), want)
