"""The protective-stop rules (pure) and the contacts MuJoCo reports for them."""
import numpy as np
import pytest

from ur_sim_driver.physics.physics import Contact
from ur_sim_driver.robot.safety import LIMIT_MARGIN, REFERENCE_TOLERANCE, ContactSafety, any_outside, limit_cause
from ur_sim_driver.robot.sim_config import sim_config_from_params
from ur_sim_driver.robot.simulator import Simulator

NAMES = tuple(f'j{i}' for i in range(6))
Q_MIN, Q_MAX = np.full(6, -1.0), np.full(6, 1.0)


def test_the_strongest_contact_above_the_limit_is_named():
    contacts = (Contact('wrist_3_link', 'floor', 20.0, 1e-4), Contact('dispenser', 'windshield_piece_03', 80.0, 6e-4),
                Contact('forearm_link', 'floor', 60.0, 1e-4))
    cause = ContactSafety(50.0, window=1).update(contacts, armed=True)
    assert cause.startswith('contact between dispenser and windshield_piece_03: force 80.0 N > 50.0 N')
    assert '0.60 mm' in cause
    assert ContactSafety(80.0, window=1).update(contacts, armed=True) is None  # above, not at, the limit
    assert ContactSafety(50.0, window=1).update((), armed=True) is None


def test_the_force_is_a_mean_over_the_window():
    safety = ContactSafety(50.0, window=5)
    spike = (Contact('dispenser', 'glass', 240.0, 1e-5),)
    assert safety.update(spike, armed=True) is None  # 48 N over 5 cycles: one sample of a rigid contact
    assert safety.update((), armed=True) is None
    cause = safety.update((Contact('dispenser', 'glass', 20.0, 1e-5),), armed=True)
    assert cause is not None and 'force 52.0 N > 50.0 N (mean over 5 cycles' in cause
    # Forces of the same pair add up in the mean; other pairs are apart.
    safety = ContactSafety(50.0, window=2)
    assert safety.update((Contact('dispenser', 'glass', 60.0, 0.0), Contact('forearm_link', 'floor', 60.0, 0.0)),
                         armed=True) is None
    assert 'dispenser and glass: force 55.0 N' in safety.update((Contact('dispenser', 'glass', 50.0, 0.0),),
                                                                armed=True)


def test_a_contact_present_when_armed_stops_only_when_it_pushes_harder():
    safety = ContactSafety(50.0, window=1, tolerance=25.0)
    elbow = ('upper_arm_link', 'wrist_3_link')
    assert safety.update((Contact(*elbow, 160.0, 1e-3),), armed=True) is not None  # the collision stops it
    # Stopped (not armed): the contact as it is now becomes the tolerated one.
    assert safety.update((Contact(*elbow, 62.0, 6e-4),), armed=False) is None
    assert safety.limit_for(elbow) == 87.0
    assert safety.update((Contact(*elbow, 80.0, 6e-4),), armed=True) is None  # unlocked: resting against it
    assert safety.update((Contact(*elbow, 40.0, 3e-4),), armed=True) is None  # moving away lowers the bar
    assert safety.limit_for(elbow) == 65.0
    assert 'force 70.0 N > 65.0 N' in safety.update((Contact(*elbow, 70.0, 4e-4),), armed=True)  # pushed back in
    # Once the bodies part, the next touch is a new contact with the plain limit.
    safety = ContactSafety(50.0, window=1, tolerance=25.0)
    safety.update((Contact(*elbow, 62.0, 6e-4),), armed=False)
    assert safety.update((), armed=True) is None
    assert safety.limit_for(elbow) == 50.0
    # Not armed, nothing stops the robot, whatever the force (powered off, brakes engaged, already stopped).
    assert safety.update((Contact(*elbow, 500.0, 1e-3),), armed=False) is None


def test_a_joint_driven_into_its_limit_stops_but_one_ending_at_it_does_not():
    q = np.zeros(6)
    q[2] = 1.0 - LIMIT_MARGIN / 2
    ref = q.copy()
    ref[2] = 1.3
    assert limit_cause(q, ref, Q_MIN, Q_MAX, NAMES).startswith('j2 driven into its position limit 1.0000 rad')
    ref[2] = 1.0  # a trajectory that ends exactly at the limit
    assert limit_cause(q, ref, Q_MIN, Q_MAX, NAMES) is None
    ref[2] = 1.3
    q[2] = 0.9  # still on its way: the servo brakes before the limit
    assert limit_cause(q, ref, Q_MIN, Q_MAX, NAMES) is None
    q[4], ref[4] = -1.0, -2.0
    assert 'j4 driven into its position limit -1.0000 rad' in limit_cause(q, ref, Q_MIN, Q_MAX, NAMES)
    # An arm braked to rest at a limit settles microradians past it; holding it there drives it no further.
    q, ref = np.zeros(6), np.zeros(6)
    q[1] = ref[1] = 1.0 + 2e-6
    assert limit_cause(q, ref, Q_MIN, Q_MAX, NAMES) is None
    ref[1] = 1.0 + 2.0 * REFERENCE_TOLERANCE
    assert limit_cause(q, ref, Q_MIN, Q_MAX, NAMES).startswith('j1 driven into its position limit 1.0000 rad')


@pytest.mark.parametrize('ur_type', ['ur5', 'ur5e', 'ur10', 'ur10e'])
def test_mujoco_reports_links_in_the_floor_with_the_floor_named(ur_type):
    # Stretched out and tilted 0.3 rad down from the shoulder: forearm and wrist reach into the floor.
    # (The contacts of the state after reset: a step would throw the arm out of the penetration.)
    sim = Simulator(sim_config_from_params({'ur_type': ur_type, 'initial_positions': [0.0, 0.3, 0.0, 0.0, 0.0, 0.0]}))
    contacts = sim.physics.contacts()
    assert contacts, 'expected contacts with the floor'
    assert all(c.other == 'floor' for c in contacts)
    assert {'forearm_link', 'wrist_3_link'} <= {c.robot_part for c in contacts}
    assert 'base_link_inertia' not in {c.robot_part for c in contacts}
    assert max(c.force for c in contacts) > 50.0
    assert max(c.depth for c in contacts) > 0.05


def test_no_contacts_at_the_default_start_with_the_windshield():
    sim = Simulator(sim_config_from_params({'tool': 'dispenser', 'scene': 'windshield'}))
    sim.physics.step(np.zeros(6))
    assert sim.physics.contacts() == ()


def test_any_outside_checks_both_bounds_of_every_element():
    lo, hi = np.array([-1.0, -2.0, -3.0]), np.array([1.0, 2.0, 3.0])
    assert not any_outside(np.array([1.0, -2.0, 0.0]), lo, hi)  # on a bound is inside
    assert any_outside(np.array([0.0, 0.0, 3.0 + 1e-12]), lo, hi)
    assert any_outside(np.array([0.0, -2.0 - 1e-12, 0.0]), lo, hi)
    frozen = np.array([0.0, 5.0, 0.0])
    frozen.flags.writeable = False  # a trajectory's arrays are read-only
    assert any_outside(frozen, lo, hi)
