"""URScript programs on the simulated robot (Simulator, RobotState and the program slot; no ROS): the interpreter's
semantics, the moves as the arm performs them, speed scaling, limits, runtime errors, and the program slot's rules
(a program replaces the one running, a dashboard stop ends it, a sec program runs at once and may not move)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from script_box import READY, Box

from ur_sim_driver.errors import ScriptError
from ur_sim_driver.robot.robot_state import EXTERNAL_CONTROL_PROGRAM, PLAYING, STOPPED
from ur_sim_driver.urscript.runner import STARTED, TEXT
from ur_sim_driver.urscript.runner import STOPPED as EV_STOPPED


def test_the_language_numbers_lists_functions_scopes_and_loops():
    box = Box()
    box.run('''def prog():
  global total = 0
  def add(a, b=10):
    return a + b
  end
  items = [1, 2, 3]
  items[1] = add(5)
  i = 0
  while True:
    i = i + 1
    if i > 3:
      break
    elif i == 2:
      continue
    end
    total = total + items[i - 1]
  end
  textmsg("total=", total)
  textmsg(items)
  textmsg(7 / 2, 6 / 3)
  textmsg(7 % 3 == 1 and not (1 > 2) xor False)
  textmsg(norm([3, 4]))
end''')
    assert box.log == ['total=4', '[1, 15, 3]', '3.52', 'True', '5']
    assert box.kinds() == [STARTED, TEXT, TEXT, TEXT, TEXT, TEXT, EV_STOPPED]


@pytest.mark.parametrize('source, line, reason', [
    ('def prog():\n  x = 1\n  foo(2)\nend', 3, "unknown function 'foo'"),
    ('def prog():\n  textmsg(y)\nend', 2, "variable 'y' is not defined"),
    ('def prog():\n  l = [1]\n  x = l[3]\nend', 3, 'index 3 is out of range'),
    ('def prog():\n  while True:\n    x = 1\n  end\nend', 2, 'infinite loop detected'),
    ('def prog():\n  set_standard_digital_out(9, True)\nend', 2, 'set_standard_digital_out: n is an integer in [0, 7]'),
    ('def prog():\n  movej([0, 0, 0])\nend', 2, 'movej: q is a list of 6 joint values'),
])
def test_a_runtime_error_stops_the_program_with_its_line_and_reason(source, line, reason):
    box = Box()
    q0 = box.sim.state().q
    box.run(source)
    (error,) = box.errors()
    assert error.line == line and reason in error.text, error
    assert box.kinds()[-1] == EV_STOPPED
    assert np.abs(box.sim.state().q - q0).max() < 1e-3  # nothing moved
    assert box.robot.program_state == STOPPED and box.robot.script is None


def test_movej_reaches_its_target_in_the_time_of_its_profile_and_scales_with_the_slider():
    durations = {}
    for factor in (1.0, 0.5):
        box = Box(factor=factor)
        target = np.array(READY) + [0.5, -0.2, 0.3, 0.1, 0.0, -0.4]
        durations[factor] = box.run(f'movej({[float(v) for v in target]}, a=1.4, v=1.05)')
        assert np.abs(box.sim.state().q - target).max() < 2e-3
        assert np.abs(np.array(box.q)).max() < 2 * np.pi
    expected = 2.0 * np.sqrt(0.5 / 1.4)  # 0.5 rad lead: a triangle at 1.4 rad/s^2
    assert durations[1.0] == pytest.approx(expected, abs=0.01)
    assert durations[0.5] == pytest.approx(2.0 * expected, abs=0.02)


def test_a_target_outside_the_joint_limits_is_refused_and_nothing_moves():
    box = Box()
    box.run('movej([0, -1.2, 1.2, -1.57, -1.57, 7.0])')
    (error,) = box.errors()
    assert 'movej: target joint 5 = 7.0000 rad is outside its limits [-6.2832, 6.2832]' in error.text
    assert np.abs(box.sim.state().q - READY).max() < 1e-3


def test_movel_moves_the_tcp_on_a_straight_line_and_tcp_pose_and_ik_agree_with_the_simulation():
    box = Box()
    box.run('''def prog():
  start = get_actual_tcp_pose()
  textmsg(start)
  q = get_inverse_kin(start)
  write_output_float_register(0, norm(q - get_actual_joint_positions()))
  movel(pose_trans(start, p[0.05, -0.08, 0.1, 0, 0, 0]), a=1.2, v=0.25)
end''')
    assert box.robot.registers.output_doubles[0] < 1e-6  # IK of the pose now: the joints now
    start = np.array([float(v) for v in box.log[0][2:-1].split(',')])
    position, quat = Box().sim.tcp_pose()
    assert np.allclose(start[:3], position, atol=1e-5)  # textmsg rounds to 6 digits
    assert np.allclose(Rotation.from_rotvec(start[3:]).as_quat(), quat, atol=1e-4) or \
        np.allclose(Rotation.from_rotvec(start[3:]).as_quat(), -quat, atol=1e-4)
    path = np.array(box.tcp)
    direction = Rotation.from_quat(quat).apply([0.05, -0.08, 0.1])
    end = position + direction
    assert np.linalg.norm(path[-1] - end) < 1e-3
    u = direction / np.linalg.norm(direction)
    off = path - position
    assert np.linalg.norm(off - np.outer(off @ u, u), axis=1).max() < 1e-3  # within 1 mm of the line


def test_speedj_runs_on_until_stopj_and_sleep_takes_its_time():
    box = Box()
    took = box.run('''def prog():
  speedj([0.3, 0, 0, 0, 0, 0], 1.5, 0.6)
  textmsg(get_actual_joint_positions()[0])
  stopj(3.0)
  sleep(0.5)
end''')
    moved = float(box.log[0])
    assert moved == pytest.approx(0.5 * 1.5 * 0.2 ** 2 + 0.3 * 0.4, abs=0.01)  # ramp 0.2 s, then 0.4 s at 0.3 rad/s
    assert took == pytest.approx(0.6 + 0.1 + 0.5, abs=0.01)
    assert np.abs(box.sim.state().qd).max() < 1e-3


def test_a_servoj_stream_follows_its_points():
    box = Box()
    box.run('''def prog():
  q = get_actual_joint_positions()
  i = 0
  while i < 100:
    q[0] = q[0] + 0.002
    servoj(q, t=0.008)
    i = i + 1
  end
  sleep(0.2)
end''')
    assert box.sim.state().q[0] == pytest.approx(0.2, abs=2e-3)


def test_registers_and_io():
    box = Box()
    box.robot.registers.input_ints[3] = 42
    box.run('''def prog():
  write_output_integer_register(1, read_input_integer_register(3) + 1)
  write_output_boolean_register(5, True)
  set_standard_digital_out(2, True)
  set_configurable_digital_out(1, True)
  set_tool_digital_out(0, True)
  set_standard_analog_out(1, 0.25)
end''')
    assert box.robot.registers.output_ints[1] == 43 and box.robot.registers.output_bits[5]
    io = box.sim.io
    assert io.digital_out[2] and io.digital_out[9] and io.digital_out[16] and not io.digital_out[0]
    assert io.analog_out[1] == pytest.approx(0.25 * 10.0)  # VOLTAGE domain: 0-10 V


def test_a_program_replaces_the_external_control_program_and_a_dashboard_stop_ends_it():
    box = Box()
    assert box.robot.program_running
    box.runner.submit('movej([0.5, -1.2, 1.2, -1.57, -1.57, 0.0])')
    assert not box.robot.program_running and box.robot.program_state == PLAYING
    assert box.robot.loaded_program == EXTERNAL_CONTROL_PROGRAM
    for _ in range(100):
        box.step()
    box.robot.stop()  # the dashboard's stop
    box.step()
    assert box.runner.current is None and box.kinds()[-1] == EV_STOPPED
    q = box.sim.state().q
    for _ in range(250):
        box.step()
    assert np.abs(box.sim.state().q - q).max() < 0.05  # it braked; no goal pulls it on


def test_a_new_program_replaces_the_running_one():
    box = Box()
    box.runner.submit('def first():\n  sleep(10)\nend')
    box.step()
    box.runner.submit('def second():\n  textmsg("second")\nend')
    stopped = [e for e in box.events if e.kind == EV_STOPPED]
    assert [(e.name, e.text) for e in stopped] == [('first', 'replaced by second')]
    box.step()
    assert box.log == ['second'] and box.runner.current is None


def test_a_secondary_program_runs_at_once_beside_the_main_one_and_may_not_move():
    box = Box()
    box.runner.submit('sec io():\n  set_standard_digital_out(1, True)\nend')
    assert box.sim.io.digital_out[1] and box.robot.program_running  # External Control plays on
    box.runner.submit('sec bad():\n  movej([0, 0, 0, 0, 0, 0])\nend')
    (error,) = box.errors()
    assert 'a secondary program (sec) cannot spend robot time' in error.text and box.robot.program_running


def test_a_program_needs_the_robot_running():
    box = Box()
    box.robot.power_off()
    with pytest.raises(ScriptError, match='robot mode is POWER_OFF; a program needs RUNNING'):
        box.runner.submit('textmsg("x")')
    assert box.events == []


def test_a_protective_stop_ends_the_program_and_it_is_not_resumed():
    box = Box()
    box.runner.submit('def slow():\n  movej([1.0, -1.2, 1.2, -1.57, -1.57, 0.0], a=0.5, v=0.3)\nend')
    for _ in range(200):
        box.step()
    box.robot.protective_stop(box.sim.time, 'a test')
    box.step()
    assert box.runner.current is None and box.robot.program_state == STOPPED and box.robot.script is None
    assert [(e.kind, e.name) for e in box.events][-1] == (EV_STOPPED, 'slow')


def test_speedl_moves_the_tool_along_its_twist_until_stopl():
    box = Box()
    start = box.sim.tcp_pose()[0].copy()
    box.run('''def prog():
  speedl([0.05, 0, -0.02, 0, 0, 0], 0.5, 1.0)
  stopl(0.5)
end''')
    moved = box.sim.tcp_pose()[0] - start
    # 0.1 s ramp up (half the speed on average), 0.9 s at speed, 0.1 s ramp down
    expected = np.array([0.05, 0.0, -0.02]) * (0.05 + 0.9 + 0.05)
    assert np.allclose(moved, expected, atol=1e-3), moved
    assert np.abs(box.sim.state().qd).max() < 1e-2


def test_text_lists_popups_and_the_tool_voltage():
    box = Box()
    box.run('''def prog():
  textmsg(str_cat("q=", [1, 2.5]))
  textmsg(str_cat(to_str(p[0.1, 0, 0, 0, 0, 0]), to_str(True)))
  textmsg(get_list_length([1, 2, 3]), get_list_length([]))
  popup("check the gripper", title="Cell", warning=True, blocking=True)
  set_tool_voltage(24)
end''')
    assert box.log == ['q=[1, 2.5]', 'p[0.1, 0, 0, 0, 0, 0]True', '30', 'popup (warning) Cell: check the gripper']
    assert box.sim.io.tool_voltage == 24
    box = Box()
    box.run('def prog():\n  set_tool_voltage(5)\nend')
    assert 'set_tool_voltage: voltage 5' in box.errors()[0].text and 'not one of 0, 12, 24 V' in box.errors()[0].text


def test_movec_moves_the_tcp_on_the_arc_through_the_via_point():
    box = Box()
    box.run('''def prog():
  start = get_actual_tcp_pose()
  via = pose_add(start, p[0.05, 0.05, 0, 0, 0, 0])
  to = pose_add(start, p[0.1, 0, 0, 0, 0, 0])
  movec(via, to, a=1.2, v=0.1)
  textmsg(pose_dist(get_actual_tcp_pose(), to) < 0.001)
  movep(start, a=1.2, v=0.1)
  textmsg(pose_dist(get_actual_tcp_pose(), start) < 0.001)
end''')
    assert box.log == ['True', 'True'], box.errors()
