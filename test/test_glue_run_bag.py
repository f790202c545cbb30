"""A glue run's bag end to end: a short glue job (three of the default waypoints, an open bead) run by the planner
node's run_job against ur_sim with the dispenser in the windshield scene, in real time; its out_dir/bag read back
with the mcap library's ROS 2 decoder (not rosbags, which wrote it): every topic with its type, counts against the
data's own stamps, every message decoded."""
import json
import threading

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from sim_harness import running_sim, yaml_params

from ur_glue_planner.execution.node import run_job
from ur_sim_driver.description.bead import from_cloud
from ur_sim_driver.description.scene import config_dir

# ur_sim's start, 5 s of motion in real time with the waits around the bead, the report without render and video:
# 15 s on an idle 2-core machine; the default timeout (pytest.ini) would do, this one says what is expected.
pytestmark = pytest.mark.timeout(180)

TYPES = {
    '/joint_states': 'sensor_msgs/msg/JointState',
    '/tf': 'tf2_msgs/msg/TFMessage',
    '/tf_static': 'tf2_msgs/msg/TFMessage',
    '/robot_description': 'std_msgs/msg/String',
    '/io_and_status_controller/io_states': 'ur_msgs/msg/IOStates',
    '/force_torque_sensor_broadcaster/wrench': 'geometry_msgs/msg/WrenchStamped',
    '/ur_sim/glue_bead': 'sensor_msgs/msg/PointCloud2',
    '/ur_glue_planner/planned_path': 'nav_msgs/msg/Path',
}
PART_SCAN = '/ur_sim/part_scan'  # where the scene has scanners (sensor_msgs/PointCloud2)


@pytest.fixture(scope='module')
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('glue_bag')
    job = yaml.safe_load((config_dir() / 'glue_job.yaml').read_text())
    job['path'].update(waypoints=job['path']['waypoints'][:3], closed=False)  # 0.18 m of bead in 1.5 s
    job.update(approach_min_duration=1.0, approach_distance=0.02, retreat_distance=0.02)
    (tmp / 'job.yaml').write_text(yaml.safe_dump(job))
    params = yaml_params(config_dir() / 'ur_sim_windshield.yaml')
    params['real_time_factor'] = 1.0
    out = tmp / 'out'
    with running_sim(**params) as h:
        code = run_job({'job': str(tmp / 'job.yaml'), 'out_dir': str(out), 'render': False, 'video': False},
                       threading.Event(), context=h.client.context)
    assert code == 0
    messages: dict[str, list] = {}
    schemas: dict[str, tuple[str, str, str]] = {}
    with open(out / 'bag' / 'bag.mcap', 'rb') as f:
        for schema, channel, message, decoded in make_reader(f, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages():
            schemas[channel.topic] = (schema.name, schema.encoding, channel.message_encoding)
            messages.setdefault(channel.topic, []).append((message.log_time * 1e-9, decoded))
    return out, messages, schemas, json.loads((out / 'summary.json').read_text())


def test_every_topic_is_there_with_its_type(run):
    out, messages, schemas, _ = run
    assert set(TYPES) <= set(messages) <= set(TYPES) | {PART_SCAN}
    for topic, name in {**TYPES, PART_SCAN: 'sensor_msgs/msg/PointCloud2'}.items():
        if topic in schemas:
            assert schemas[topic] == (name, 'ros2msg', 'cdr'), topic
    # a rosbag2 directory: ros2 bag's metadata beside the .mcap, with the same counts
    meta = yaml.safe_load((out / 'bag' / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['storage_identifier'] == 'mcap' and meta['relative_file_paths'] == ['bag.mcap']
    assert {t['topic_metadata']['name']: t['message_count'] for t in meta['topics_with_message_count']} == \
        {topic: len(m) for topic, m in messages.items()}


def test_the_streams_hold_every_cycle_on_the_robots_clock(run):
    _, messages, _, _ = run
    states = messages['/joint_states']
    # In real time the stamps count from the system clock (about 1.8e9 s): differences in whole nanoseconds.
    ns = np.array([m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec for _, m in states], dtype=np.int64)
    stamps = ns * 1e-9
    period = np.median(np.diff(ns)) * 1e-9
    assert period == pytest.approx(1.0 / 125.0, rel=1e-6)  # the CB3 UR5's controller
    expected = (ns[-1] - ns[0]) * 1e-9 / period + 1.0
    assert 0.95 * expected <= len(states) <= expected + 0.5  # no cycle recorded twice, hardly any missed
    assert stamps[-1] - stamps[0] > 4.8  # the whole motion (4.8 s planned)
    # Log times are the simulated clock at arrival: a cycle's stamp each, never decreasing. How far one lies from its
    # message's own stamp is how late either topic came, which the machine's load sets (a burst of joint states
    # before the clock under load: 64 ms early), so it is not judged here.
    log = np.array([t for t, _ in states])
    cycles = (log - stamps[0]) / period
    assert np.all(np.abs(cycles - np.round(cycles)) < 1e-3) and np.all(np.diff(log) >= 0.0)
    assert all(len(m.name) == 6 and len(m.position) == 6 for _, m in states)
    for topic in ('/io_and_status_controller/io_states', '/force_torque_sensor_broadcaster/wrench'):
        assert len(messages[topic]) >= 0.9 * len(states), topic  # every cycle too
    wrench = messages['/force_torque_sensor_broadcaster/wrench'][-1][1]
    assert wrench.header.frame_id == 'tool0_controller'
    assert any(d.pin == 16 and d.state for _, io in messages['/io_and_status_controller/io_states']
               for d in io.digital_out_states)  # the gun's output was on during the bead
    assert len(messages['/tf']) >= 20.0 * (stamps[-1] - stamps[0])  # at least the joints' frames at 20 Hz


def test_the_latched_topics_once_and_the_bead_as_judged(run):
    out, messages, _, summary = run
    assert len(messages['/robot_description']) == 1 and '<robot name="ur5"' in messages['/robot_description'][0][1].data
    static = {t.child_frame_id for _, m in messages['/tf_static'] for t in m.transforms}
    assert len(messages['/tf_static']) >= 1 and {'base', 'tool0'} <= static
    (_, path), = messages['/ur_glue_planner/planned_path']
    assert path.header.frame_id == 'base_link' and len(path.poses) == 76  # 1.5 s of bead at 0.02 s
    tips = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z] for p in path.poses])
    assert np.linalg.norm(np.diff(tips, axis=0), axis=1).sum() == pytest.approx(summary['bead_length_m'], rel=0.05)
    beads = messages['/ur_sim/glue_bead']
    assert len(beads) >= 2  # the cleared glass, then the bead growing
    final = np.load(out / 'bead.npz')['times']  # the bead the report judged, read by the run once the flow ended
    np.testing.assert_array_equal(np.sort(from_cloud(beads[-1][1]).times), final)  # the bag's last bead is it
