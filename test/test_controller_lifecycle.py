"""The controller manager's lifecycle services on its controllers (ros2_control 4.46): load, configure, cleanup,
unload, with upstream's refusals."""
from __future__ import annotations

from ur_sim_driver.controllers import controller_lifecycle as lc
from ur_sim_driver.controllers.controller_manager import STRICT, ControllerManager, ControllerSpec


def _manager() -> ControllerManager:
    return ControllerManager([ControllerSpec('jsb', 'broadcaster'), ControllerSpec('fpc', 'forward', ('j/position',))],
                             active=('jsb',))


def _errors(step) -> list[str]:
    return [line.text for line in step.log if line.level == 'error']


def test_load_configure_activate_then_back():
    cm = _manager()
    assert lc.load(cm, ControllerSpec('jtc', 'jtc', ('j/velocity',))).ok
    assert cm.state('jtc') == 'unconfigured' and list(cm.specs) == ['jsb', 'fpc', 'jtc']
    assert not cm.plan(['jtc'], [], STRICT).ok  # not configured yet
    assert lc.configure(cm, 'jtc').ok and cm.state('jtc') == 'inactive'
    cm.apply(cm.plan(['jtc'], [], STRICT))
    assert cm.is_active('jtc')
    for op, text in ((lc.configure, "Controller 'jtc' can not be configured from 'active' state."),
                     (lc.cleanup, "Controller 'jtc' can not be cleaned-up from 'active' state."),
                     (lc.unload, "Could not unload controller with name 'jtc' because it is still active")):
        step = op(cm, 'jtc')
        assert not step.ok and _errors(step) == [text] and cm.is_active('jtc')
    cm.apply(cm.plan([], ['jtc'], STRICT))
    assert lc.cleanup(cm, 'jtc').ok and cm.state('jtc') == 'unconfigured'
    assert lc.cleanup(cm, 'jtc').ok  # already unconfigured: nothing to do
    assert lc.unload(cm, 'jtc').ok and 'jtc' not in cm.specs and 'jtc' not in cm.states


def test_reconfigure_cleans_up_first_and_inactive_unloads():
    cm = _manager()
    step = lc.configure(cm, 'fpc')
    assert step.ok and "Controller 'fpc' is cleaned-up before configuring" in [line.text for line in step.log]
    assert lc.unload(cm, 'fpc').ok and list(cm.specs) == ['jsb']


def test_refusals_name_the_controller():
    cm = _manager()
    step = lc.load(cm, ControllerSpec('jsb', 'broadcaster'))
    assert not step.ok
    assert _errors(step) == ["A controller named 'jsb' was already loaded inside the controller manager"]
    for op, verb in ((lc.configure, 'configure'), (lc.cleanup, 'cleanup'), (lc.unload, 'unload')):
        step = op(cm, 'ghost')
        assert not step.ok
        assert _errors(step) == [f"Could not {verb} controller with name 'ghost' because no controller with this name "
                                 'exists']
    assert cm.active_names() == ('jsb',)
