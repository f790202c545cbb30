"""The studio's message log and robot status line: what they say, and that their boxes keep one height."""
import re

from ur_glue_planner.studio.messages import SHOWN, MessageLog, log_html
from ur_glue_planner.studio.robot_status import GONE_AFTER, no_ros_status, robot_status, status_html


def _height(markup: str) -> str:
    return re.search(r'height:([0-9.]+em)', markup).group(1)


def test_the_box_shows_the_newest_lines_first_and_keeps_its_height():
    log = MessageLog()
    empty = log_html(log.lines())
    for k in range(12):
        log.say(f'line {k}')
    assert log.lines() == [f'line {k}' for k in range(11, 11 - SHOWN, -1)]
    assert len(log.history) == 12 and log.history[0] == 'line 0'
    full = log_html(log.lines())
    assert _height(empty) == _height(full) and 'overflow-y:auto' in full  # the box never grows


def test_a_new_action_clears_the_errors_of_the_last():
    log = MessageLog()
    log.begin('planning ...')
    log.say('planning failed: waypoint 13: out of reach (48 mm)')
    log.begin('planning ...')
    assert log.lines() == ['planning ...']
    assert any('failed' in m for m in log.history)  # kept in the history, not in the box


def test_errors_are_red_and_text_is_escaped():
    markup = log_html(['run failed: <goal>', 'planned: bead 2.2 m', 'run succeeded: bead completed (error_code 0)'])
    assert 'color:#c0262d">run failed: &lt;goal&gt;' in markup
    assert '<div>planned: bead 2.2 m</div>' in markup
    assert '<div>run succeeded: bead completed (error_code 0)</div>' in markup


def test_the_robot_is_awaited_then_live_then_gone_after_the_timeout():
    assert robot_status('/live', 100.0, None, False) == (
        'waiting', 'waiting for /live/joint_states and /live/robot_description')
    assert robot_status('', 100.0, None, True) == ('waiting', 'waiting for /joint_states')
    assert robot_status('', 100.0, 99.0, False)[1] == 'waiting for /robot_description (/joint_states arrive)'
    assert robot_status('', 100.0, 100.0 - GONE_AFTER, True) == ('live', 'robot live: /joint_states')
    state, text = robot_status('/ur10', 100.0, 88.0, True)
    assert state == 'gone' and text.startswith('robot gone: no /ur10/joint_states for 12 s (more than 3 s)')
    assert robot_status('', 100.0, 100.0 - GONE_AFTER - 0.01, True)[0] == 'gone'


def test_the_status_line_keeps_its_height():
    heights = {_height(status_html(*s)) for s in (no_ros_status(), robot_status('', 1.0, None, False),
                                                  robot_status('/a_long_namespace', 1e4, 1.0, True))}
    assert len(heights) == 1
    assert 'data-state="gone"' in status_html(*robot_status('', 10.0, 1.0, True))
