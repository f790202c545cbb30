"""examples/startup_like_a_real_robot.py against ur_sim started powered off, over DDS."""
import sys
from pathlib import Path

from rclpy.node import Node
from sim_harness import running_sim

from ur_sim_driver.robot.robot_state import RUNNING

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'examples'))
import startup_like_a_real_robot as example  # noqa: E402


def test_the_start_up_example_runs_from_power_off_to_the_wrench():
    # Free-running: the example waits on the client library's own (wall-clock) deadlines.
    with running_sim(lockstep=False, start_powered_off=True, tool='dispenser') as h:
        node = Node('startup_example', context=h.client.context)
        try:
            result = example.run(node, gun_pin=16)
        finally:
            node.destroy_node()
        assert result['robot_mode'] == RUNNING
        assert result['error_code'] == 0
        assert result['gun'] == [True, False]
        # At rest the sensor carries the dispenser (0.5 kg): about 4.9 N.
        assert 4.5 < sum(f * f for f in result['force']) ** 0.5 < 5.3
