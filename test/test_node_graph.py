"""The ROS graph a client sees: each of ur_sim's node names once. The trajectory controllers' nodes are ur_sim's (as
each controller is a node in ros2_control); their actions are served by the gateway process from a node of its own.
(Only ur_sim's names are counted: the domain is this test process's, and what earlier tests left is not the subject.)
"""
import pytest
from rclpy.action import get_action_server_names_and_types_by_node
from sim_harness import running_sim, wait_still

from ur_sim_driver.gateway.gateway_process import NODE_NAME

pytestmark = pytest.mark.timeout(120)

CONTROLLERS = ('scaled_joint_trajectory_controller', 'joint_trajectory_controller',
               'passthrough_trajectory_controller')


def _names(node) -> list[str]:
    return [f"{namespace.rstrip('/')}/{name}" for name, namespace in node.get_node_names_and_namespaces()]


def _gateway_actions(node) -> set[str]:
    try:
        return {name for name, _ in get_action_server_names_and_types_by_node(node, NODE_NAME, '/')}
    except Exception:  # noqa: BLE001 -- rclpy raises until the node is discovered
        return set()


def test_every_node_name_is_unique_and_the_gateway_serves_the_controllers_actions():
    with running_sim() as h:
        want = {f'/{c}/follow_joint_trajectory' for c in CONTROLLERS}
        wait_still(lambda: want <= _gateway_actions(h.client), what="the gateway node's action servers")
        expected = {f'/{NODE_NAME}', '/ur_sim', *(f'/{c}' for c in CONTROLLERS)}
        wait_still(lambda: expected <= set(_names(h.client)), what='the nodes of ur_sim and its gateway')
        ours = {f'/{n.get_name()}' for n in h.sim.nodes()} | {f'/{NODE_NAME}'}

        def twice() -> list[str]:
            names = _names(h.client)
            return sorted(n for n in ours if names.count(n) > 1)
        # The graph may still list a node of a process an earlier test in this domain ended (its participant's
        # removal reaches this one later, under load seconds later); a name ur_sim itself has twice stays.
        try:
            wait_still(lambda: not twice(), timeout=20.0, what='each of ur_sim\'s node names once in the graph')
        except TimeoutError:
            pytest.fail(f'node names that exist more than once: {twice()}')
