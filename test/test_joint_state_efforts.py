"""/joint_states effort over DDS as the driver reports it: the motor currents [A] by default (the driver at a16a268
reads RTDE actual_current), the torques less gravity [N m] with use_currents_as_efforts false."""
from __future__ import annotations

import numpy as np
import pytest
from sim_harness import running_sim

POSE = [0.0, -1.0, 0.0, -1.57, 0.0, 0.0]  # the arm leaning out: the shoulder holds some 40 N m


def _last_effort(h) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The newest /joint_states effort after 0.2 s at rest, with the currents of the gravity torques [A] (the arm at
    rest: its drives hold it up) and the drive torques now [N m]."""
    rec = h.record()
    h.wait_sim_time(0.2)
    h.stop_recording()
    with h.sim.host.lock:
        sim = h.sim.sim
        return np.array(rec.effort[-1]), sim.gravity_compensation() / sim.params.torque_constant, \
            sim.state().effort.copy()


@pytest.mark.timeout(120)
def test_joint_states_effort_is_the_motor_currents_by_default_and_torques_less_gravity_when_asked():
    with running_sim(initial_positions=POSE) as h:
        effort, currents, torques = _last_effort(h)
    np.testing.assert_allclose(effort, currents, atol=0.01)  # [A]: a cycle's jitter at rest
    assert abs(torques[1]) > 10.0 and abs(effort[1] - torques[1]) > 5.0  # a current, not the torque [N m]
    with running_sim(initial_positions=POSE, use_currents_as_efforts=False) as h:
        effort, _, torques = _last_effort(h)
    assert abs(torques[1]) > 10.0 and np.abs(effort).max() < 0.01  # at rest, no payload: gravity compensated
