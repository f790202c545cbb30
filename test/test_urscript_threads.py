"""URScript threads on the simulated robot (no ROS), stepped cycle by cycle: each thread runs every control cycle until
it spends robot time, critical sections keep the others out, kill and join, motion from any thread (the last command
wins), the infinite-loop error in a thread, halt, and the program ending with its main thread."""
from __future__ import annotations

import numpy as np
from script_box import COUNTER, READY, Box

from ur_sim_driver.robot.robot_state import STOPPED
from ur_sim_driver.urscript.runner import STARTED
from ur_sim_driver.urscript.runner import STOPPED as EV_STOPPED


def test_threads_run_every_cycle_beside_the_main_program():
    box = Box()
    took = box.run('def prog():\n' + COUNTER + '''  t = run counter()
  sleep(0.1)
  kill t
  textmsg("ticks ", ticks)
  seen = ticks
  sleep(0.02)
  textmsg("after kill ", ticks - seen)
end''')
    # 0.1 s at 500 Hz: the main thread sleeps 50 cycles, the counter runs in each, from the one it started in
    assert box.log == ['ticks 50', 'after kill 0']
    assert abs(took - 0.12) < 0.005


def test_join_waits_for_the_thread_and_return_ends_it():
    box = Box()
    box.run('''def prog():
  thread worker():
    sleep(0.05)
    textmsg("worker done")
    return 5
    textmsg("never")
  end
  w = run worker()
  textmsg("started ", w != 0)
  join w
  textmsg("joined")
  join w
  textmsg("joined again")
end''')
    assert box.log == ['started True', 'worker done', 'joined', 'joined again']


def test_a_critical_section_keeps_the_other_threads_out_while_it_runs_and_not_while_it_spends_time():
    """As the Client Library's External Control program needs it: its main thread waits for a command in a
    blocking read inside a section while its servo thread commands the arm every cycle."""
    box = Box()
    box.run('def prog():\n' + COUNTER + '''  t = run counter()
  sleep(0.01)
  enter_critical
  before = ticks
  k = 0
  while k < 1000:
    k = k + 1
  end
  unchanged = ticks - before
  sleep(0.02)
  during = ticks - before
  exit_critical
  textmsg("unchanged ", unchanged)
  textmsg("during ", during)
  kill t
end''')
    assert box.log == ['unchanged 0', 'during 10']


def test_kill_ends_the_thread_and_the_threads_it_started():
    box = Box()
    box.run('''def prog():
  global inner_ticks = 0
  global inner = 0
  thread child():
    while True:
      inner_ticks = inner_ticks + 1
      sync()
    end
  end
  thread parent():
    inner = run child()
    while True:
      sync()
    end
  end
  p = run parent()
  sleep(0.01)
  kill p
  seen = inner_ticks
  sleep(0.01)
  textmsg(inner_ticks - seen)
  kill p
  kill 0
  textmsg("killing twice, or 0, is harmless")
end''')
    assert box.log == ['0', 'killing twice, or 0, is harmless']


def test_motion_from_a_thread_and_the_last_command_wins():
    box = Box()
    a = [float(v) for v in np.array(READY) + [0.4, 0, 0, 0, 0, 0]]
    b = [float(v) for v in np.array(READY) + [-0.3, 0, 0, 0, 0, 0]]
    box.run(f'''def prog():
  thread mover():
    movej({a}, a=1.4, v=1.05)
    textmsg("mover's movej returned")
  end
  m = run mover()
  sleep(0.2)
  movej({b}, a=1.4, v=1.05)
  textmsg("main's movej returned")
  join m
end''')
    # the main thread's move replaced the thread's: the thread's call returned, the arm went to b
    assert box.log == ["mover's movej returned", "main's movej returned"]
    assert np.abs(box.sim.state().q - b).max() < 1e-3
    assert max(q[0] for q in box.q) < a[0] - 0.1  # a was never reached


def test_the_program_ends_with_its_main_thread_and_its_threads_with_it():
    box = Box()
    took = box.run('''def prog():
  thread forever():
    while True:
      sync()
    end
  end
  run forever()
  sleep(0.01)
end''')
    assert abs(took - 0.01) < 0.005
    assert box.kinds() == [STARTED, EV_STOPPED] and box.robot.program_state == STOPPED


def test_halt_in_a_thread_ends_the_program():
    box = Box()
    took = box.run('''def prog():
  thread stopper():
    sleep(0.02)
    halt
  end
  run stopper()
  while True:
    sync()
  end
end''')
    assert abs(took - 0.02) < 0.005 and not box.errors()


def test_an_infinite_loop_in_a_thread_is_a_runtime_error_at_its_line():
    box = Box()
    box.run('''def prog():
  thread spin():
    x = 0
    while True:
      x = x + 1
    end
  end
  run spin()
  sleep(10)
end''')
    (error,) = box.errors()
    assert error.line == 4 and 'infinite loop' in error.text
    assert box.robot.program_state == STOPPED


def test_thread_errors_name_what_is_wrong():
    for source, line, reason in [
        ('def prog():\n  run nobody()\nend', 2, "no thread named 'nobody'"),
        ('def prog():\n  kill "t"\nend', 2, 'kill: t is not a thread handle'),
        ('def prog():\n  exit_critical\nend', 2, 'exit_critical without enter_critical'),
        ('def prog():\n  global h = 0\n  thread a():\n    sleep(1)\n  end\n  thread b():\n    join h\n  end\n'
         '  h = run a()\n  run b()\n  sleep(0.1)\nend', 7, 'a thread can only join the threads it started'),
    ]:
        box = Box()
        box.run(source)
        (error,) = box.errors()
        assert error.line == line and reason in error.text, error


def test_matrices_one_line_programs_and_polyscope_labels():
    box = Box()
    box.run('def prog(): m = [[1, 2], [3, 4]] m[0, 1] = 9 textmsg(m[1, 0], m[0, 1]) textmsg(m) end')
    assert box.log == ['39', '[[1, 9], [3, 4]]']
    box = Box()
    box.run('def prog():\n  $ 1 "Robot Program"\n  textmsg("a")\n  $ 2 "Wait: 0.01"\n  sleep(0.01)\n'
            '  undefined_thing()\nend')
    assert box.log == ['a'] and box.errors()[0].line == 6  # the label lines keep the numbering
