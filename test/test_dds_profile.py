"""The controller interface process's Fast DDS profile: when it applies, what it says, and that a process using it
gives a large received sample's memory back (in a process of its own: Fast DDS reads profiles once a process)."""
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from ros_helpers import ros_context
from std_msgs.msg import UInt8MultiArray

from ur_sim_driver.gateway.dds_profile import applies, free_received_samples, profile_text

SIZE = 16_000_000  # [bytes] one sample, as large as a 100,000-point goal and more


def test_profile_text_keeps_rmw_fastrtps_publication_mode():
    assert '<kind>SYNCHRONOUS</kind>' in profile_text(None)
    assert '<kind>SYNCHRONOUS</kind>' in profile_text('bogus')  # rmw_fastrtps: unknown is SYNCHRONOUS
    assert '<kind>ASYNCHRONOUS</kind>' in profile_text('ASYNCHRONOUS')
    assert 'publishMode' not in profile_text('AUTO')  # Fast DDS's own default
    text = profile_text(None)
    assert text.count('<historyMemoryPolicy>DYNAMIC</historyMemoryPolicy>') == 1  # readers only
    assert text.count('PREALLOCATED_WITH_REALLOC') == 3  # discovery histories and writers, as rmw_fastrtps sets


def test_the_profile_stays_out_of_a_users_fast_dds_settings(tmp_path):
    assert applies({}, tmp_path)
    assert applies({'RMW_IMPLEMENTATION': 'rmw_fastrtps_cpp'}, tmp_path)
    assert not applies({'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}, tmp_path)
    for switch in ('RMW_FASTRTPS_USE_QOS_FROM_XML', 'FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE'):
        assert not applies({switch: '1'}, tmp_path)
    (tmp_path / 'DEFAULT_FASTRTPS_PROFILES.xml').write_text('<profiles/>')
    assert not applies({}, tmp_path)


def test_free_received_samples_points_fast_dds_at_the_profile():
    env = {'RMW_FASTRTPS_PUBLICATION_MODE': 'ASYNCHRONOUS'}
    path = free_received_samples(env)
    try:
        assert env['FASTRTPS_DEFAULT_PROFILES_FILE'] == str(path)
        assert env['RMW_FASTRTPS_USE_QOS_FROM_XML'] == '1'
        assert path.read_text() == profile_text('ASYNCHRONOUS')
    finally:
        path.unlink()
    assert free_received_samples({'FASTRTPS_DEFAULT_PROFILES_FILE': '/somewhere/mine.xml'}) is None


_RECEIVER = '''
import sys, time
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import UInt8MultiArray
from ur_sim_driver.gateway.dds_profile import free_received_samples
from ur_sim_driver.gateway.memory import trim_heap, use_mmap_for_large_blocks

def rss():
    for line in open('/proc/self/status'):
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) / 1024.0

use_mmap_for_large_blocks()
profile = free_received_samples() if sys.argv[1] == 'profile' else None
rclpy.init()
node = Node('profile_receiver')
sizes = []
sub = node.create_subscription(UInt8MultiArray, 'big', lambda data: sizes.append(len(data)),
                               QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE), raw=True)
if profile is not None:
    profile.unlink()
deadline = time.monotonic() + 30
while sub.get_publisher_count() == 0 and time.monotonic() < deadline:
    rclpy.spin_once(node, timeout_sec=0.05)
for _ in range(20):
    rclpy.spin_once(node, timeout_sec=0.05)
before = rss()
print('READY', flush=True)
while not sizes and time.monotonic() < deadline + 30:
    rclpy.spin_once(node, timeout_sec=0.05)
trim_heap()
time.sleep(0.5)
print('RESULT', sizes[0] if sizes else 0, before, rss(), flush=True)
'''


@pytest.mark.parametrize('mode', ['profile', 'rmw defaults'])
def test_a_received_large_sample_is_given_back_with_the_profile(mode):
    receiver = subprocess.Popen([sys.executable, '-c', _RECEIVER, mode.split()[0]], stdout=subprocess.PIPE,
                                text=True, cwd=Path(__file__).parent)
    try:
        with ros_context() as ctx:
            node = Node('profile_sender', context=ctx)
            pub = node.create_publisher(UInt8MultiArray, 'big', QoSProfile(depth=1,
                                                                            reliability=ReliabilityPolicy.RELIABLE))
            assert receiver.stdout.readline().strip() == 'READY'
            msg = UInt8MultiArray(data=bytes(range(256)) * (SIZE // 256))
            pub.publish(msg)
            line = receiver.stdout.readline().split()
            time.sleep(0.1)
            node.destroy_node()
        assert line[0] == 'RESULT' and int(line[1]) > SIZE  # the whole sample arrived
        kept = float(line[3]) - float(line[2])  # [MB]
        if mode == 'profile':
            assert kept < 4.0, f'{kept:.1f} MB kept after a {SIZE / 1e6:.0f} MB sample'
        else:  # what the profile is for: rmw_fastrtps's reader pool keeps the sample's buffer
            assert kept > 0.8 * SIZE / 2**20, f'only {kept:.1f} MB kept'
    finally:
        receiver.kill()
        receiver.wait()
