"""Tests of ur_sim_driver.motion.start_stamp: what ur_sim says about a start stamped far ahead."""

from ur_sim_driver.motion.start_stamp import FAR_FUTURE, far_start

WALL = 1.8e9  # [s since the epoch] a wall clock in 2027
SIM = 12.5  # [s] ur_sim's simulated time a few seconds after start


def test_a_stamp_within_the_window_is_not_said():
    assert far_start(SIM + FAR_FUTURE, SIM, WALL) is None
    assert far_start(SIM - 3.0, SIM, WALL) is None


def test_a_stamp_some_seconds_ahead_is_a_plain_wait_not_a_clock_error():
    note = far_start(SIM + 6.0, SIM, WALL)
    assert note is not None and not note.wall_clock
    assert '6.0 s after the simulated time now (12.500 s)' in note.text
    assert 'use_sim_time' not in note.text


def test_a_wall_clock_stamp_on_simulated_time_blames_the_clock():
    note = far_start(WALL + 0.2, SIM, WALL)
    assert note is not None and note.wall_clock
    assert 'use_sim_time:=true' in note.text


def test_on_wall_time_a_stamp_far_ahead_is_not_a_clock_error():
    # ur_sim on the wall clock (use_sim_time false): a stamp near the wall clock is the right clock
    note = far_start(WALL + 20.0, WALL, WALL)
    assert note is not None and not note.wall_clock
