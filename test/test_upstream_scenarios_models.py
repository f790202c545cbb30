"""The driver's robot-model scenario (ur_robot_driver/test/integration_test_robot_models.py at a16a268) against ur_sim
started as that file's launch description starts the driver: the robot description and ros2_control_node with the
hardware component left unconfigured, beside a URSim of the model (booted powered off); no dashboard sequence, as
upstream has none. docs/upstream_tests.md maps each upstream test method to the tests that cover it."""
from __future__ import annotations

import pytest
from cm_helpers import ControllerManagerClient
from lifecycle_msgs.msg import State
from sim_harness import running_sim

from ur_sim_driver.description.params import UR_TYPES
from ur_sim_driver.robot.robot_state import POWER_OFF


@pytest.mark.timeout(60)
@pytest.mark.parametrize('robot_type, ur_type', [(t, t) for t in UR_TYPES] + [('ur5e', 'ur20')],
                         ids=[*UR_TYPES, 'ur5e-as-ur20'])
def test_each_model_configures_from_unconfigured_and_a_wrong_one_does_not(robot_type, ur_type):
    """The driver configured for `ur_type`, the robot a `robot_type` booted powered off, the hardware left
    unconfigured at start (ros2_control_node's hardware_components_initial_state): configuring it succeeds when the
    two agree, and fails, leaving it unconfigured, when they do not."""
    with running_sim(ur_type=ur_type, simulated_ur_type=robot_type, start_powered_off=True, headless_mode=True,
                     hardware_components_initial_state={'unconfigured': [ur_type]}) as h:
        assert h.sim.robot.robot_mode == POWER_OFF
        cm = ControllerManagerClient(h)
        (component,) = cm.components()
        assert (component.name, component.state.id) == (ur_type, State.PRIMARY_STATE_UNCONFIGURED)
        response = cm.set_component_state(ur_type, State.PRIMARY_STATE_INACTIVE, 'inactive')
        if robot_type == ur_type:
            assert response.ok and (response.state.id, response.state.label) == (State.PRIMARY_STATE_INACTIVE,
                                                                                 'inactive')
        else:
            assert not response.ok and response.state.id == State.PRIMARY_STATE_UNCONFIGURED
            (component,) = cm.components()
            assert component.state.id == State.PRIMARY_STATE_UNCONFIGURED
