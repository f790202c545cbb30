"""The planner's reader of ur_sim's bead (``/ur_sim/glue_bead``) over DDS: the final bead is the publisher's newest,
taken from a new subscription's latched sample, in the planner's world frame."""
import threading

import numpy as np
import pytest
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from ros_helpers import ros_context
from sensor_msgs.msg import PointCloud2

from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.bead_listener import BEAD_TOPIC, BeadListener
from ur_sim_driver.description.bead import BASE_IN_WORLD, Bead, to_cloud

pytestmark = pytest.mark.timeout(60)


def _bead(n: int) -> Bead:
    t = np.arange(n) * 0.002
    points = np.column_stack([0.4 + 0.1 * t, 0.1 * np.ones(n), 0.02 * np.ones(n)])
    return Bead(points, 0.006 * np.ones(n), 0.003 * np.ones(n), 10.0 + t)


@pytest.fixture
def nodes():
    from rclpy.executors import MultiThreadedExecutor

    with ros_context() as context:
        sim = Node('bead_sim', context=context)
        client = Node('bead_client', context=context)
        executor = MultiThreadedExecutor(num_threads=2, context=context)
        executor.add_node(sim)
        executor.add_node(client)
        spinner = threading.Thread(target=executor.spin, daemon=True)
        spinner.start()
        try:
            yield sim, client, spinner
        finally:
            executor.shutdown(timeout_sec=2.0)
            spinner.join(timeout=5.0)
            sim.destroy_node()
            client.destroy_node()


def test_final_is_the_newest_bead_published(nodes):
    sim, client, _ = nodes
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    pub = sim.create_publisher(PointCloud2, BEAD_TOPIC, latched)
    listener = BeadListener(client)
    stamp = sim.get_clock().now().to_msg()
    for n in (3, 40, 500):  # growing, as ur_sim publishes it; the last is the flow's end
        pub.publish(to_cloud(_bead(n), 'base', stamp))
    final = listener.final(timeout=20.0)
    assert len(final.times) == 500
    np.testing.assert_allclose(final.times, _bead(500).times)
    expected = _bead(500).points @ BASE_IN_WORLD[:3, :3].T  # base -> the planner's base_link
    np.testing.assert_allclose(final.points, expected, atol=1e-6)
    assert sum(1 for s in client.subscriptions if s.topic_name == BEAD_TOPIC) == 1  # the listener's own only


def test_final_again_and_again_leaves_the_clients_executor_spinning(nodes):
    """The reader comes and goes while the client's executor spins in another thread (a subscription destroyed
    under a spinning executor used to kill that thread, and every later call of the client went unanswered)."""
    sim, client, spinner = nodes
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    pub = sim.create_publisher(PointCloud2, BEAD_TOPIC, latched)
    pub.publish(to_cloud(_bead(50), 'base', sim.get_clock().now().to_msg()))
    listener = BeadListener(client)
    for _ in range(30):
        assert len(listener.final(timeout=20.0).times) == 50
        assert spinner.is_alive()


def test_final_without_a_bead_names_the_topic(nodes):
    _, client, _ = nodes
    listener = BeadListener(client)
    with pytest.raises(ClientError, match=f'no bead on {BEAD_TOPIC} within 0.5 s'):
        listener.final(timeout=0.5)
    assert sum(1 for s in client.subscriptions if s.topic_name == BEAD_TOPIC) == 1


def test_a_namespaced_simulator_s_bead_is_read_under_its_namespace(nodes):
    sim, client, _ = nodes
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE)
    pub = sim.create_publisher(PointCloud2, '/ur10' + BEAD_TOPIC, latched)  # as ur_sim prefixes it
    listener = BeadListener(client, namespace='/ur10')
    assert (listener.topic, listener.clear_service) == ('/ur10/ur_sim/glue_bead', '/ur10/ur_sim/clear_glue_bead')
    pub.publish(to_cloud(_bead(7), 'base', sim.get_clock().now().to_msg()))
    assert len(listener.final(timeout=20.0).times) == 7
