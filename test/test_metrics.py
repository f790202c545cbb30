"""Bead metrics on hand-made data whose answers are known."""
import numpy as np

from ur_glue_planner.report.metrics import point_to_polyline_distance, speed_stats, tracking_error


def test_speed_stats_counts_length_within_the_band():
    x = np.linspace(0.0, 1.0, 101)
    positions = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    speeds = np.full(101, 0.15)
    speeds[:10] = 0.10  # the first 0.1 m (segments 0..9) is slow
    stats = speed_stats(positions, speeds, 0.15, cruise=np.arange(101) >= 10)
    assert abs(stats['fraction_within_band'] - 0.9) < 1e-12
    assert stats['min'] == 0.15 and stats['max'] == 0.15 and abs(stats['length'] - 1.0) < 1e-12


def test_point_to_polyline_distance():
    line = np.array([[0.0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]])
    pts = np.array([[0.5, 0.2, 0.0], [2.0, 0.5, 0.0], [-1.0, 0.0, 0.0], [1.0, 0.5, 0.3]])
    assert np.allclose(point_to_polyline_distance(pts, line), [0.2, 1.0, 1.0, 0.3])


def test_tracking_error_interpolates_the_plan():
    t_plan = np.array([0.0, 1.0])
    q_plan = np.array([[0.0, 0.0], [1.0, 2.0]])
    t_meas = np.array([0.25, 0.5, 2.0])  # the last sample is outside the plan and ignored
    q_meas = np.array([[0.25, 0.6], [0.4, 1.0], [9.0, 9.0]])
    assert np.allclose(tracking_error(t_meas, q_meas, t_plan, q_plan), [0.1, 0.1])
