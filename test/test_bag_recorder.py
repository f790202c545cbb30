"""The run's bag recorder (execution/bag_recorder.py) and the planned path (execution/planned_path.py): the pure
parts (topics, QoS choice, clock parsing, bag directory, message definitions against the installed interfaces'
hashes), a recording over DDS without a simulator read back with the mcap library (not rosbags, the writer), and
a recorder that cannot start leaving the run to go on."""
import json
import os
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from ros_helpers import ros_context
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from ur_msgs.msg import Digital, IOStates

from ur_glue_planner.execution import bag_recorder as rec
from ur_glue_planner.execution.planned_path import planned_path, planned_path_topic, tf_prefix_of
from ur_glue_planner.execution.run import start_bag

pytestmark = pytest.mark.timeout(60)

LATCHED = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)


def test_the_drivers_topics_take_the_namespace_and_tf_stays_absolute():
    names = {t.name: t for t in rec.recorded_topics('/ur10')}
    assert set(names) == {'/ur10/joint_states', '/tf', '/tf_static', '/ur10/robot_description',
                          '/ur10/io_and_status_controller/io_states', '/ur10/force_torque_sensor_broadcaster/wrench',
                          '/ur10/ur_sim/glue_bead', '/ur10/ur_sim/part_scan', '/ur10/ur_glue_planner/planned_path'}
    latched = {n for n, t in names.items() if t.latched}
    assert latched == {'/tf_static', '/ur10/robot_description', '/ur10/ur_sim/glue_bead',
                       '/ur10/ur_glue_planner/planned_path'}
    assert planned_path_topic('') == '/ur_glue_planner/planned_path'
    assert {t.name for t in rec.recorded_topics('')} >= {'/joint_states', '/ur_sim/glue_bead'}


def test_the_subscription_matches_every_publisher_and_gets_the_latched_messages():
    latched = rec.RecordedTopic('/a', 'std_msgs/msg/String', latched=True)
    stream = rec.RecordedTopic('/b', 'std_msgs/msg/String')
    volatile = QoSProfile(depth=10)
    best_effort = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
    # no publisher seen yet: the topic's own QoS
    assert rec.subscription_qos(latched, []).durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert rec.subscription_qos(stream, []).durability == DurabilityPolicy.VOLATILE
    assert rec.subscription_qos(stream, []).reliability == ReliabilityPolicy.RELIABLE
    # what the publishers offer wins: a latched reader would not match a volatile writer, a reliable one not a
    # best-effort writer
    assert rec.subscription_qos(stream, [LATCHED]).durability == DurabilityPolicy.TRANSIENT_LOCAL
    assert rec.subscription_qos(latched, [LATCHED, volatile]).durability == DurabilityPolicy.VOLATILE
    assert rec.subscription_qos(stream, [volatile, best_effort]).reliability == ReliabilityPolicy.BEST_EFFORT


@pytest.mark.parametrize('t', [0.0, 1.25, 1_790_000_000.999999999])
def test_the_clock_is_read_from_its_cdr(t):
    ns = round(t * 1e9)
    msg = Clock(clock=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000))
    assert rec.clock_ns(serialize_message(msg)) == ns


def test_an_earlier_bag_is_replaced_and_anything_else_is_kept(tmp_path):
    bag = tmp_path / 'run' / 'bag'
    rec.prepare_bag_dir(bag)  # nothing there: the parent is made
    assert bag.parent.is_dir() and not bag.exists()
    bag.mkdir()
    (bag / 'metadata.yaml').write_text('x')
    (bag / 'bag.mcap').write_bytes(b'x')
    rec.prepare_bag_dir(bag)
    assert not bag.exists()
    bag.mkdir()
    (bag / 'notes.txt').write_text('mine')
    with pytest.raises(FileExistsError, match='not a bag'):
        rec.prepare_bag_dir(bag)
    assert (bag / 'notes.txt').read_text() == 'mine'


def _installed_hash(typename: str) -> str:
    pkg, _, name = typename.split('/')
    for prefix in os.environ['AMENT_PREFIX_PATH'].split(os.pathsep):
        path = Path(prefix) / 'share' / pkg / 'msg' / f'{name}.json'
        if path.is_file():
            hashes = json.loads(path.read_text())['type_hashes']
            return next(h['hash_string'] for h in hashes if h['type_name'] == typename)
    raise LookupError(typename)


@pytest.mark.parametrize('typename', sorted({t.type for t in rec.recorded_topics()}))
def test_every_definition_hashes_as_the_installed_interface(typename):
    # ur_msgs is not in rosbags' typestore: read from its installed .msg files, with the types it uses
    msgdef, rihs01 = rec.MessageTypes().definition(typename)
    assert rihs01 == _installed_hash(typename)
    if typename == 'ur_msgs/msg/IOStates':
        assert 'MSG: ur_msgs/Digital' in msgdef and 'MSG: ur_msgs/Analog' in msgdef


def test_an_unknown_type_is_named():
    with pytest.raises(LookupError, match='no_such_msgs/msg/Thing'):
        rec.MessageTypes().definition('no_such_msgs/msg/Thing')


def test_the_planned_path_is_the_bead_tips_in_base_link():
    tip_pos = np.array([[0.1, 0.5, 0.2], [0.11, 0.5, 0.2], [0.12, 0.51, 0.21]])
    tip_quat = np.array([[1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.5, 0.5], [0.0, 0.0, 0.0, 1.0]])  # w first
    plan = SimpleNamespace(bead=SimpleNamespace(tip_pos=tip_pos, tip_quat=tip_quat))
    msg = planned_path(plan, tf_prefix_of(('my_ur_shoulder_pan_joint', 'my_ur_elbow_joint')) + 'base_link', 12.5)
    assert msg.header.frame_id == 'my_ur_base_link' and (msg.header.stamp.sec, msg.header.stamp.nanosec) == (12, 5e8)
    assert len(msg.poses) == 3 and all(p.header.frame_id == 'my_ur_base_link' for p in msg.poses)
    np.testing.assert_allclose([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in msg.poses],
                               tip_pos)
    o = msg.poses[2].pose.orientation
    assert (o.x, o.y, o.z, o.w) == (0.0, 0.0, 1.0, 0.0)
    assert tf_prefix_of(('shoulder_pan_joint',)) == '' and tf_prefix_of(()) == ''


def _wait(condition, timeout: float = 20.0, what: str = 'condition') -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f'timed out waiting for {what}'
        time.sleep(0.005)


def _read(path: Path) -> dict[str, list]:
    """topic -> [(schema name, log time [ns], decoded message)], with the mcap library's own ROS 2 decoder."""
    out: dict[str, list] = {}
    with open(path, 'rb') as f:
        for schema, channel, message, decoded in make_reader(f, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages():
            assert channel.message_encoding == 'cdr' and schema.encoding == 'ros2msg'
            out.setdefault(channel.topic, []).append((schema.name, message.log_time, decoded))
    return out


def test_a_recording_over_dds_reads_back_with_the_mcap_library(tmp_path):
    lines = []
    with ros_context() as context:
        driver = Node('fake_driver', namespace='ur10', context=context)
        try:
            description = driver.create_publisher(String, 'robot_description', LATCHED)
            description.publish(String(data='<robot name="ur5"/>'))  # before the recorder exists: latched
            clock = driver.create_publisher(Clock, '/clock', 10)
            states = driver.create_publisher(JointState, 'joint_states', 10)
            io = driver.create_publisher(IOStates, 'io_and_status_controller/io_states', 10)
            recorder = rec.BagRecorder(context, tmp_path / 'bag', '/ur10', log=lines.append)
            recorder.start(first_message_timeout=0.0)
            try:
                _wait(lambda: min(p.get_subscription_count() for p in (clock, states, io)) > 0, what='matching')
                for k in range(5):  # before any clock: logged at the first clock's time
                    states.publish(JointState(name=['shoulder_pan_joint'], position=[0.1 * k]))
                clock.publish(Clock(clock=Time(sec=10)))
                for k in range(5, 8):
                    states.publish(JointState(name=['shoulder_pan_joint'], position=[0.1 * k]))
                io.publish(IOStates(digital_out_states=[Digital(pin=16, state=True)]))
                _wait(lambda: recorder.counts.get('/ur10/joint_states', 0) == 8 and len(recorder.counts) == 3,
                      what='the messages in the bag')
            finally:
                counts = recorder.close()
        finally:
            driver.destroy_node()
    assert counts == {'/ur10/joint_states': 8, '/ur10/robot_description': 1,
                      '/ur10/io_and_status_controller/io_states': 1}
    assert sorted(p.name for p in (tmp_path / 'bag').iterdir()) == ['bag.mcap', 'metadata.yaml']
    assert any('simulated clock' in line for line in lines) and any('10 messages on 3 topics' in line for line in lines)
    bag = _read(tmp_path / 'bag' / 'bag.mcap')
    assert {t: len(m) for t, m in bag.items()} == counts  # no publisher, no topic: the wrench is absent
    assert [m[0] for m in bag['/ur10/joint_states']] == ['sensor_msgs/msg/JointState'] * 8
    assert [m[2].position[0] for m in bag['/ur10/joint_states']] == pytest.approx([0.1 * k for k in range(8)])
    assert all(m[1] == 10_000_000_000 for ms in bag.values() for m in ms)  # simulated time, none at 0
    assert bag['/ur10/robot_description'][0][2].data == '<robot name="ur5"/>'
    name, _, io_msg = bag['/ur10/io_and_status_controller/io_states'][0]
    assert name == 'ur_msgs/msg/IOStates' and io_msg.digital_out_states[0].pin == 16
    assert io_msg.digital_out_states[0].state


def test_what_arrived_before_the_first_clock_is_written_when_the_clock_comes(tmp_path):
    # DDS orders each topic, not the topics between them: the first clock may be the last message taken
    with ros_context() as context:
        driver = Node('fake_driver', context=context)
        try:
            clock = driver.create_publisher(Clock, '/clock', 10)
            states = driver.create_publisher(JointState, 'joint_states', 10)
            recorder = rec.BagRecorder(context, tmp_path / 'bag', log=lambda _: None).start(first_message_timeout=0.0)
            try:
                _wait(lambda: min(p.get_subscription_count() for p in (clock, states)) > 0, what='matching')
                for k in range(3):
                    states.publish(JointState(name=['shoulder_pan_joint'], position=[0.1 * k]))
                _wait(lambda: recorder.held == 3, what='the joint states held for the clock')
                assert recorder.counts == {}
                clock.publish(Clock(clock=Time(sec=7)))
                _wait(lambda: recorder.counts.get('/joint_states', 0) == 3, what='the held joint states written')
                assert recorder.held == 0
            finally:
                recorder.close()
        finally:
            driver.destroy_node()
    bag = _read(tmp_path / 'bag' / 'bag.mcap')
    assert [m[1] for m in bag['/joint_states']] == [7_000_000_000] * 3


def test_a_run_that_cannot_record_goes_on_and_says_why(tmp_path):
    taken = tmp_path / 'bag'
    taken.write_text('not a directory')
    lines = []
    ur = SimpleNamespace(node=None, prefix='', joint_names=('shoulder_pan_joint',), now=lambda: 0.0, context=None)
    plan = SimpleNamespace(bead=SimpleNamespace(tip_pos=np.zeros((1, 3)), tip_quat=np.array([[1.0, 0, 0, 0]])))
    assert start_bag(ur, plan, taken, log=lines.append) is None
    assert lines[0].startswith('planned path: not published')
    assert lines[1].startswith('bag: not recording (FileExistsError') and lines[1].endswith('the run goes on')
    assert taken.read_text() == 'not a directory'
