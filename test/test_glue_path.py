"""Bead path geometry: corner blends, arc-length sampling, orientation SLERP."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_common.quaternions import matrix_from_quat, quat_from_matrix
from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.errors import PlanningError
from ur_glue_planner.orientation import (
    rot_x,
    rot_y,
    rot_z,
    rotation_angle,
    rotation_from_zyx_euler,
    rotation_vectors,
    slerp,
)
from ur_glue_planner.path.glue_path import GluePath, build_glue_path, polyline_corners

R_DEFAULT = rotation_from_zyx_euler(*DEFAULT_ORIENTATION_ZYX)


@pytest.fixture(scope="module", params=[False, True], ids=["open", "closed"])
def seed_path(request) -> GluePath:
    return build_glue_path(DEFAULT_WAYPOINTS, R_DEFAULT, max_deviation=0.01,
                           closed=request.param)


# ---------------------------------------------------------------- DESIGN facts (section 6)
def test_seed_polyline_is_2_27_m_with_three_corners_of_80_to_97_deg():
    length, turns = polyline_corners(DEFAULT_WAYPOINTS)
    assert length == pytest.approx(2.27, abs=0.005)
    big = np.flatnonzero(turns > math.radians(30))
    assert len(big) == 3
    assert np.all((np.degrees(turns[big]) > 80) & (np.degrees(turns[big]) < 97))
    assert list(big + 1) == [5, 12, 16]  # waypoints at the top-left, top-right, bottom-right
    assert np.linalg.norm(DEFAULT_WAYPOINTS[-1] - DEFAULT_WAYPOINTS[0]) < 0.01  # closes


def test_default_orientation_is_rx_minus_60_deg():
    np.testing.assert_allclose(R_DEFAULT, rot_x(-math.pi / 3), atol=1e-15)


def test_zyx_euler_matches_eul2rotm():
    # eul2rotm([pi/2 0 0]) is a pure yaw; [z y x] composes Rz * Ry * Rx
    np.testing.assert_allclose(rotation_from_zyx_euler(math.pi / 2, 0, 0),
                               [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    z, y, x = 0.3, -0.4, 1.1
    np.testing.assert_allclose(rotation_from_zyx_euler(z, y, x), rot_z(z) @ rot_y(y) @ rot_x(x))


# ---------------------------------------------------------------- geometry
def test_path_passes_each_waypoint_within_its_blend_deviation(seed_path):
    pos, _, _ = seed_path.sample(seed_path.waypoint_s)
    dist = np.linalg.norm(pos - DEFAULT_WAYPOINTS, axis=1)
    assert dist.max() <= 0.01 + 1e-12
    for c in seed_path.corners:
        assert dist[c.waypoint] == pytest.approx(c.deviation, abs=1e-12)
        assert c.radius * (1 / math.cos(c.turn_angle / 2) - 1) == pytest.approx(c.deviation)
    if not seed_path.closed:  # open paths start and end exactly on their end waypoints
        assert dist[0] < 1e-15 and dist[-1] < 1e-15


def test_path_passes_exactly_through_segment_midpoints(seed_path):
    v = seed_path.vertices
    for i, (s0, s1) in enumerate(seed_path.straight_s):
        mid = 0.5 * (v[i] + v[(i + 1) % len(v)])
        start, _, _ = seed_path.sample(s0)
        s_mid = s0 + np.linalg.norm(mid - start)
        assert s0 - 1e-12 <= s_mid <= s1 + 1e-12
        np.testing.assert_allclose(seed_path.sample(s_mid)[0], mid, atol=1e-12)


def test_tangent_is_unit_and_continuous_at_every_join(seed_path):
    s = np.linspace(0.0, seed_path.length, 5001)
    _, tan, _ = seed_path.sample(s)
    np.testing.assert_allclose(np.linalg.norm(tan, axis=1), 1.0, atol=1e-14)
    eps = 1e-9
    joins = seed_path.piece_s[1:-1]
    p_lo, t_lo, _ = seed_path.sample(joins - eps)
    p_hi, t_hi, _ = seed_path.sample(joins + eps)
    assert np.abs(t_hi - t_lo).max() < 1e-6  # C1: no kink anywhere (curvature <= 60 1/m)
    assert np.abs(p_hi - p_lo).max() < 3 * eps


def test_arc_length_sampling_is_uniform_on_straights_and_arcs(seed_path):
    ds = 1e-3
    bounds = seed_path.piece_s
    for k in range(len(bounds) - 1):
        s = np.arange(bounds[k] + 1e-6, bounds[k + 1] - 1e-6, ds)
        if len(s) < 2:
            continue
        chord = np.linalg.norm(np.diff(seed_path.sample(s)[0], axis=0), axis=1)
        r = seed_path.piece_radius[k]
        expected = 2 * r * math.sin(ds / (2 * r)) if seed_path.piece_arc[k] else ds
        np.testing.assert_allclose(chord, expected, rtol=1e-9)


def test_blends_shorten_the_polyline_by_the_cut_corners(seed_path):
    v = seed_path.vertices
    segs = np.diff(np.vstack([v, v[:1]]) if seed_path.closed else v, axis=0)
    cut = sum(2 * c.setback - c.radius * c.turn_angle for c in seed_path.corners)
    assert seed_path.length == pytest.approx(np.linalg.norm(segs, axis=1).sum() - cut, abs=1e-12)
    assert 2.2 < seed_path.length < 2.28


def test_curvature_vector_points_to_the_arc_centre(seed_path):
    arc = int(np.flatnonzero(seed_path.piece_arc & (seed_path.piece_radius < 0.05))[0])
    s = 0.5 * (seed_path.piece_s[arc] + seed_path.piece_s[arc + 1])
    p, t, kappa = seed_path.sample(s)
    kvec = seed_path.curvature_vector(s)
    assert kappa == pytest.approx(1 / seed_path.piece_radius[arc])
    assert np.linalg.norm(kvec) == pytest.approx(kappa) and abs(kvec @ t) < 1e-12
    h = 1e-6
    dt = (seed_path.sample(s + h)[1] - seed_path.sample(s - h)[1]) / (2 * h)
    np.testing.assert_allclose(dt, kvec, rtol=1e-5)


def test_closed_loop_wraps_smoothly():
    path = build_glue_path(DEFAULT_WAYPOINTS, R_DEFAULT, closed=True)
    assert len(path.vertices) == 21  # the last waypoint repeats the first
    assert len(path.corners) == 21 and path.corners[-1].waypoint == 0
    p0, t0, _ = path.sample(0.0)
    p1, t1, _ = path.sample(path.length)
    np.testing.assert_allclose(p0, p1, atol=1e-12)
    np.testing.assert_allclose(t0, t1, atol=1e-12)
    assert path.waypoint_s[-1] == path.waypoint_s[0]
    with pytest.raises(ValueError):
        build_glue_path(DEFAULT_WAYPOINTS, R_DEFAULT).sample(3.0)


def test_blend_size_is_limited_by_neighbouring_segments():
    zigzag = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.04, 0], [0.2, 0.04, 0.01]], float)
    path = build_glue_path(zigzag, np.eye(3), blend_radius=1.0, max_deviation=None)
    for c in path.corners:
        assert c.limited_by == "segments"
        assert c.setback == pytest.approx(0.02)  # half of the 4 cm middle segment
    assert path.straight_s[1, 1] - path.straight_s[1, 0] == pytest.approx(0.0, abs=1e-12)
    capped = build_glue_path(zigzag, np.eye(3), blend_radius=0.005, max_deviation=None)
    assert [c.radius for c in capped.corners] == [0.005, 0.005]


def test_bad_waypoints_raise():
    with pytest.raises(PlanningError, match="waypoints 1 and 2"):
        build_glue_path(np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0]], float), np.eye(3))
    with pytest.raises(PlanningError, match="waypoint 1 turns"):
        build_glue_path(np.array([[0, 0, 0], [1, 0, 0], [0.5, 0, 0]], float), np.eye(3))
    with pytest.raises(ValueError):
        build_glue_path(np.zeros((3, 2)), np.eye(3))


# ---------------------------------------------------------------- orientation
def test_slerp_endpoints_unit_norm_and_constant_rate():
    q0 = quat_from_matrix(rot_z(0.2))
    q1 = quat_from_matrix(rot_x(1.2) @ rot_z(0.2))
    t = np.linspace(0.0, 1.0, 11)
    q = slerp(q0, q1, t)
    np.testing.assert_allclose(q[0], q0, atol=1e-15)
    np.testing.assert_allclose(q[-1], q1, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    angles = rotation_angle(matrix_from_quat(q[:-1]), matrix_from_quat(q[1:]))
    np.testing.assert_allclose(angles, 0.12, atol=1e-12)
    # -q1 is the same rotation: still the short way round
    np.testing.assert_allclose(slerp(q0, -q1, 0.5), q[5], atol=1e-15)


def test_quaternion_matrix_round_trip_including_half_turns():
    rng = np.random.default_rng(1)
    mats = [rot_x(math.pi), rot_y(math.pi), rot_z(math.pi), rot_x(math.pi) @ rot_z(0.5)]
    mats += [rotation_from_zyx_euler(*a) for a in rng.uniform(-3, 3, (20, 3))]
    mats = np.array(mats)
    np.testing.assert_allclose(matrix_from_quat(quat_from_matrix(mats)), mats, atol=1e-14)
    # the turn from a to b in world axes: b = exp([v]x) a, with |v| the angle between them
    qa, qb = quat_from_matrix(mats[4]), quat_from_matrix(mats[5])
    v = rotation_vectors(qa, qb)
    angle = np.linalg.norm(v)
    assert angle == pytest.approx(rotation_angle(mats[4], mats[5]), abs=1e-14)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]) / angle
    turn = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k  # Rodrigues, written out to check SciPy's
    np.testing.assert_allclose(turn @ mats[4], mats[5], atol=1e-14)


@pytest.mark.parametrize("closed", [False, True])
def test_orientation_meets_waypoint_keys_and_is_smooth(closed):
    tilts = 0.3 * np.sin(np.linspace(0.0, 2 * math.pi, len(DEFAULT_WAYPOINTS)))
    rots = np.array([R_DEFAULT @ rot_y(a) for a in tilts])
    path = build_glue_path(DEFAULT_WAYPOINTS, rots, closed=closed)
    used = len(path.vertices)  # a closed loop drops the repeated last waypoint
    got = path.orientation(path.waypoint_s[:used])
    assert rotation_angle(got, rots[:used]).max() < 1e-9
    s = np.linspace(0.0, path.length, 20001)
    rate = rotation_angle(path.orientation(s[:-1]), path.orientation(s[1:])) / np.diff(s)
    keys = path.key_s
    key_rate = rotation_angle(matrix_from_quat(path.key_q[:-1]),
                              matrix_from_quat(path.key_q[1:])) / np.diff(keys)
    assert rate.max() < 2.0 * key_rate.max()  # blends do not overshoot
    # the rate changes gradually (C1), also across the keys: no steps between samples
    assert np.abs(np.diff(rate)).max() < 0.01 * key_rate.max()
    if closed:
        assert rotation_angle(path.orientation(0.0), path.orientation(path.length)) < 1e-12


def test_constant_orientation_stays_constant(seed_path):
    rots = seed_path.orientation(np.linspace(0.0, seed_path.length, 101))
    np.testing.assert_allclose(rots, np.broadcast_to(R_DEFAULT, rots.shape), atol=1e-12)
