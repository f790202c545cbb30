"""Seed 1's method as the baseline: per-segment sample counts rounded down, SLERP poses, a minimum-jerk
spline through all samples, and the whole plan on the default job."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ur_glue_planner.defaults import DEFAULT_WAYPOINTS
from ur_glue_planner.job import parse_job
from ur_glue_planner.motion.plan import plan_job
from ur_glue_planner.motion.seed1 import min_jerk_spline, seed1_samples, seed1_waypoints
from ur_glue_planner.orientation import rot_x, rotation_angle


def test_segments_round_down_to_whole_samples():
    points = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.1, 0.0449, 0.0]])
    rots = np.array([np.eye(3), rot_x(0.3), rot_x(0.3)])
    pos, rot, seg, speeds = seed1_samples(points, rots, 0.15, 0.02)
    # 0.1 m at 0.15 m/s is 0.667 s: 33 intervals (0.66 s); 0.0449 m is 0.299 s: 14 intervals
    assert np.bincount(seg).tolist() == [33, 15]  # the last sample (the end waypoint) belongs to the last segment
    np.testing.assert_allclose(speeds, [0.1 / 0.66, 0.0449 / 0.28])
    np.testing.assert_allclose(pos[[0, 33, -1]], points)
    np.testing.assert_allclose(pos[1] - pos[0], [0.1 / 33, 0.0, 0.0])
    # SLERP: the rotation angle grows linearly along the first segment
    np.testing.assert_allclose(rotation_angle(rots[0], rot[:34]), 0.3 * np.arange(34) / 33, atol=1e-9)


def test_default_waypoints_give_the_seeds_segment_speeds():
    wps, rots = seed1_waypoints(DEFAULT_WAYPOINTS, np.repeat(np.eye(3)[None], len(DEFAULT_WAYPOINTS), 0), True)
    assert len(wps) == 22  # the last waypoint is 6 mm from the first: the seed's list already closes
    speeds = seed1_samples(wps, rots, 0.15, 0.02)[3]
    assert speeds.min() >= 0.15 and speeds.max() < 0.157


def test_min_jerk_spline_interpolates_and_starts_and_ends_at_rest():
    t = np.arange(12) * 0.02
    q = np.column_stack([np.sin(3 * t), t ** 2])
    spline = min_jerk_spline(t, q)
    np.testing.assert_allclose(spline(t), q, atol=1e-12)
    for order in (1, 2):
        np.testing.assert_allclose(spline(t[[0, -1]], order), 0.0, atol=1e-9)
    # C4 at the interior samples (a quintic spline): the 4th derivative has no jump there
    eps = 1e-7
    d4 = spline(t[1:-1] + eps, 4) - spline(t[1:-1] - eps, 4)
    assert np.abs(d4).max() < 1e-3 * np.abs(spline(t, 4)).max()


@pytest.fixture(scope='module')
def seed_plan():
    job = dataclasses.replace(parse_job({}), method='seed1')
    return plan_job(job, np.radians([0.0, -90.0, 0.0, -90.0, 0.0, 0.0]))


def test_seed1_plan_walks_the_waypoints_unblended(seed_plan):
    bead = seed_plan.bead
    assert seed_plan.method == 'seed1' and seed_plan.run_up == 0.0
    # every waypoint is visited (corners are not rounded off)
    for w in seed_plan.waypoints:
        assert np.linalg.norm(bead.tip_pos - w, axis=1).min() < 1e-5
    assert bead.times[-1] == pytest.approx(0.02 * (len(bead.times) - 1))
    assert np.allclose(bead.qd[[0, -1]], 0.0) and np.allclose(bead.qdd[[0, -1]], 0.0)
    mid = (bead.times > 1.0) & (bead.times < bead.times[-1] - 1.0)
    assert np.median(bead.tcp_speed[mid]) == pytest.approx(0.15, rel=0.05)
    d = seed_plan.dispense
    assert d.t_arrive == 0.0 and d.t_on == pytest.approx(-d.lead) and math.isclose(d.s_end, bead.s[-1])
