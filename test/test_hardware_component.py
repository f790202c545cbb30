"""The hardware component's lifecycle (ros2_control 4.46's resource manager): transitions, interface availability,
what runs in each state, and a failing transition."""
from __future__ import annotations

import pytest

from ur_sim_driver.controllers import hardware_component as hc

CMD = ('j1/position', 'j1/velocity')
STATE = ('j1/position', 'j1/velocity', 'j1/effort')


def _component(state=hc.ACTIVE, check=None) -> hc.HardwareComponent:
    return hc.HardwareComponent('ur5e', 'ur_robot_driver/URPositionHardwareInterface', CMD, STATE, state, check)


@pytest.mark.parametrize(('start', 'target', 'steps'), [
    (hc.ACTIVE, hc.INACTIVE, ('deactivate',)),
    (hc.ACTIVE, hc.UNCONFIGURED, ('deactivate', 'cleanup')),
    (hc.ACTIVE, hc.FINALIZED, ('deactivate', 'shutdown')),
    (hc.INACTIVE, hc.UNCONFIGURED, ('cleanup',)),
    (hc.INACTIVE, hc.ACTIVE, ('activate',)),
    (hc.UNCONFIGURED, hc.ACTIVE, ('configure', 'activate')),
    (hc.UNCONFIGURED, hc.INACTIVE, ('configure',)),
    (hc.UNCONFIGURED, hc.FINALIZED, ('shutdown',)),
    (hc.ACTIVE, hc.ACTIVE, ()),
])
def test_transitions(start, target, steps):
    c = _component(start)
    result = c.set_state(target)
    assert result.ok and result.steps == steps and c.state == target
    assert [text for _, text in result.log] == [t for s in steps for t in (
        f"'{s}' hardware 'ur5e' ", f"Successful '{s}' of hardware 'ur5e'")]


def test_label_names_the_target_when_the_id_is_zero():
    c = _component()
    assert c.set_state(0, 'inactive').ok and (c.state, c.label) == (hc.INACTIVE, 'inactive')
    bad = c.set_state(0, 'sleeping')
    assert not bad.ok and c.state == hc.INACTIVE and "valid: unconfigured (1)" in bad.log[0][1]
    assert not c.set_state(13).ok  # a transition state is no target


def test_availability_and_what_runs():
    c = _component()
    assert (c.available, c.reads, c.writes) == (True, True, True)
    c.set_state(hc.INACTIVE)
    # Upstream leaves an inactive component's interfaces available (a TODO there); read() runs, write() does not.
    assert (c.available, c.reads, c.writes) == (True, True, False)
    assert c.rejects_start(('j1/position',)).startswith("Component 'ur5e' is in INACTIVE state")
    assert c.rejects_start(('other/position',)) is None
    c.set_state(hc.UNCONFIGURED)
    assert (c.available, c.reads, c.writes) == (False, False, False)


def test_finalized_can_only_be_destroyed():
    c = _component()
    assert c.set_state(hc.FINALIZED).ok
    for target in (hc.UNCONFIGURED, hc.INACTIVE, hc.ACTIVE):
        result = c.set_state(target)
        assert not result.ok and result.log == (('warn', "hardware 'ur5e' is in finalized state and can be only "
                                                          'destroyed.'),)
    assert c.set_state(hc.FINALIZED).ok and c.state == hc.FINALIZED


def test_a_failing_transition_stops_there():
    refuse = {'configure': 'the connected robot is a UR20'}
    c = _component(hc.UNCONFIGURED, check=lambda name, step: refuse.get(step))
    result = c.set_state(hc.ACTIVE)
    assert not result.ok and result.steps == ('configure',) and c.state == hc.UNCONFIGURED
    assert result.log[-2:] == (('error', 'the connected robot is a UR20'),
                               ('error', "Failed to 'configure' hardware 'ur5e'"))


def test_bad_initial_state():
    with pytest.raises(ValueError, match='unconfigured \\(1\\), inactive \\(2\\), active \\(3\\)'):
        _component(hc.FINALIZED)
