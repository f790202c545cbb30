"""CdrTemplate: the bytes it renders decode to exactly the message rclpy would have serialized.

(Bytes are compared through deserialization: CDR's alignment padding is not part of the message, and rclpy's
serializer leaves whatever its buffer held there.)"""
from __future__ import annotations

import numpy as np
import pytest
from control_msgs.msg import JointTrajectoryControllerState
from geometry_msgs.msg import PoseStamped, TransformStamped, WrenchStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import deserialize_message, serialize_message
from ros_helpers import executor_with, ros_context, spin_until
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage

from ur_sim_driver.controllers.cdr_template import CdrTemplate
from ur_sim_driver.errors import UrSimError

NAMES = ['my_ur_shoulder_pan_joint', 'my_ur_shoulder_lift_joint', 'my_ur_elbow_joint', 'my_ur_wrist_1_joint',
         'my_ur_wrist_2_joint', 'my_ur_wrist_3_joint']


def _same(data: bytes, expected: object) -> bool:
    """`data` decodes to `expected`, and is as long as rclpy's serialization of it."""
    return (deserialize_message(data, type(expected)) == expected
            and len(data) == len(serialize_message(expected)))


def _stamp(rng: np.random.Generator) -> tuple[int, int]:
    return int(rng.integers(0, 2**31 - 1)), int(rng.integers(0, 999_999_999))


def test_joint_state_matches_rclpy_for_random_values() -> None:
    template = CdrTemplate(JointState(name=NAMES, position=[0.0] * 6, velocity=[0.0] * 6, effort=[0.0] * 6),
                           stamps=('header.stamp',), floats=('position', 'velocity', 'effort'))
    rng = np.random.default_rng(1)
    for _ in range(20):
        values, stamp = rng.normal(size=18) * 10.0 ** rng.integers(-6, 6), _stamp(rng)
        msg = JointState(name=NAMES, position=values[:6].tolist(), velocity=values[6:12].tolist(),
                         effort=values[12:].tolist())
        msg.header.stamp.sec, msg.header.stamp.nanosec = stamp
        assert _same(template.render(values, stamp), msg)


def test_nested_scalars_and_indexed_paths() -> None:
    axes = ('x', 'y', 'z'), ('x', 'y', 'z', 'w')
    pose = PoseStamped()
    pose.header.frame_id = 'my_ur_base'
    pose_t = CdrTemplate(pose, stamps=('header.stamp',), floats=(
        *(f'pose.position.{a}' for a in axes[0]), *(f'pose.orientation.{a}' for a in axes[1])))
    tf = TransformStamped(child_frame_id='tool0_controller')
    tf.header.frame_id = 'base'
    tf_t = CdrTemplate(TFMessage(transforms=[tf]), stamps=('transforms[0].header.stamp',), floats=(
        *(f'transforms[0].transform.translation.{a}' for a in axes[0]),
        *(f'transforms[0].transform.rotation.{a}' for a in axes[1])))
    rng = np.random.default_rng(2)
    values, stamp = rng.normal(size=7), _stamp(rng)
    back = deserialize_message(pose_t.render(values, stamp), PoseStamped)
    assert (back.header.stamp.sec, back.header.stamp.nanosec) == stamp and back.header.frame_id == 'my_ur_base'
    p, o = back.pose.position, back.pose.orientation
    assert [p.x, p.y, p.z, o.x, o.y, o.z, o.w] == values.tolist()
    back_tf = deserialize_message(tf_t.render(values, stamp), TFMessage).transforms[0]
    t, r = back_tf.transform.translation, back_tf.transform.rotation
    assert [t.x, t.y, t.z, r.x, r.y, r.z, r.w] == values.tolist()
    assert back_tf.child_frame_id == 'tool0_controller' and back_tf.header.stamp.sec == stamp[0]


def test_controller_state_wrench_float_and_clock() -> None:
    state = JointTrajectoryControllerState(joint_names=NAMES)
    fields = [('reference', 'positions'), ('reference', 'velocities'), ('reference', 'accelerations'),
              ('feedback', 'positions'), ('error', 'velocities'), ('output', 'effort')]
    for point, field in fields:
        setattr(getattr(state, point), field, [0.0] * 6)
    template = CdrTemplate(state, stamps=('header.stamp',),
                           floats=(*(f'{p}.{f}' for p, f in fields), 'speed_scaling_factor'))
    rng = np.random.default_rng(3)
    values, stamp = rng.normal(size=37), _stamp(rng)
    expected = JointTrajectoryControllerState(joint_names=NAMES, speed_scaling_factor=values[-1])
    for k, (point, field) in enumerate(fields):
        setattr(getattr(expected, point), field, values[6 * k:6 * k + 6].tolist())
    expected.header.stamp.sec, expected.header.stamp.nanosec = stamp
    assert _same(template.render(values, stamp), expected)

    wrench = CdrTemplate(WrenchStamped(), stamps=('header.stamp',),
                         floats=tuple(f'wrench.{v}.{a}' for v in ('force', 'torque') for a in 'xyz'))
    w = WrenchStamped()
    w.wrench.force.x, w.wrench.torque.z = 3.5, -0.25
    w.header.stamp.sec = 7
    assert _same(wrench.render([3.5, 0, 0, 0, 0, -0.25], (7, 0)), w)

    assert _same(CdrTemplate(Float64(), floats=('data',)).render((42.5,)), Float64(data=42.5))
    clock = CdrTemplate(Clock(), stamps=('clock',))
    expected_clock = Clock()
    expected_clock.clock.sec, expected_clock.clock.nanosec = 12, 345
    assert _same(clock.render((), (12, 345)), expected_clock)


def test_the_prototype_is_left_as_it_was() -> None:
    msg = JointState(name=NAMES, position=[1.0] * 6)
    msg.header.stamp.sec = 5
    CdrTemplate(msg, stamps=('header.stamp',), floats=('position',))
    assert msg.position.tolist() == [1.0] * 6 and msg.header.stamp.sec == 5


def test_publish_needs_a_publisher() -> None:
    with pytest.raises(UrSimError, match='without a publisher'):
        CdrTemplate(Float64(), floats=('data',)).publish((1.0,))


def test_unknown_field_is_named() -> None:
    with pytest.raises(UrSimError, match="'pose.positon.x'"):
        CdrTemplate(PoseStamped(), floats=('pose.positon.x',))
    with pytest.raises(UrSimError, match="'header.stmp'"):
        CdrTemplate(PoseStamped(), stamps=('header.stmp',))


def test_a_topic_is_sent_only_while_a_subscription_is_matched() -> None:
    """listened(): what DDS would deliver to. A volatile topic without a matched reader reaches no one, so the loop
    skips it; a transient-local one is always sent (a late joiner gets the last sample)."""
    with ros_context() as ctx:
        pub_node, sub_node = Node('cdr_pub', context=ctx), Node('cdr_sub', context=ctx)
        with executor_with(ctx, pub_node, sub_node) as executor:
            template = CdrTemplate(Float64(), floats=('data',),
                                   publisher=pub_node.create_publisher(Float64, 'cdr_listened', 10))
            latched = CdrTemplate(Float64(), floats=('data',), publisher=pub_node.create_publisher(
                Float64, 'cdr_latched', QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)))
            assert not template.listened()
            assert latched.listened()
            received: list[float] = []
            subscription = sub_node.create_subscription(Float64, 'cdr_listened', lambda m: received.append(m.data),
                                                        10)
            spin_until(executor, template.listened, 30.0, 'the subscription matched')
            template.publish((2.5,))
            spin_until(executor, lambda: received, 30.0, 'the message')
            assert received == [2.5]
            sub_node.destroy_subscription(subscription)
            spin_until(executor, lambda: not template.listened(), 30.0, 'the subscription unmatched')


def test_a_pair_per_stamp_and_negative_durations():
    """Each Time or Duration field its own (sec, nanosec); a negative Duration (before a trajectory's start) keeps its
    int32 sec."""
    from ur_sim_driver.motion import conversions as conv
    proto = JointTrajectoryControllerState(joint_names=NAMES)
    proto.reference.positions = [0.0] * 6
    template = CdrTemplate(proto, stamps=('header.stamp', 'reference.time_from_start', 'feedback.time_from_start'),
                           floats=('reference.positions',))
    values = np.linspace(-1.0, 1.0, 6)
    stamps = (12, 500, *conv.duration_parts(-0.3), *conv.duration_parts(2.25))
    msg = deserialize_message(template.render(values, stamps), JointTrajectoryControllerState)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (12, 500)
    assert (msg.reference.time_from_start.sec, msg.reference.time_from_start.nanosec) == (-1, 700_000_000)
    assert conv.duration_to_sec(msg.feedback.time_from_start) == pytest.approx(2.25)
    assert list(msg.reference.positions) == pytest.approx(values.tolist())
