"""Bead waypoints of a job: seed list with standoff, or the glass outline with a tilted tool."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur_glue_planner.defaults import DEFAULT_WAYPOINTS
from ur_glue_planner.job import parse_job
from ur_glue_planner.orientation import rot_x, rot_z, rotation_angle
from ur_glue_planner.scene.waypoints import align_axis, job_waypoints, tool_axis, windshield_model
from ur_glue_planner.scene.windshield import DEFAULT_WINDSHIELD


def test_dispenser_nozzle_is_the_tip_y_axis():
    # DESIGN 6: tip = tool0 * Rx(+90 deg), so tool0's z is the tip's y
    np.testing.assert_allclose(tool_axis("dispenser"), [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(tool_axis("none"), [0.0, 0.0, 1.0])


def test_job_pose_places_the_default_glass():
    model = windshield_model(parse_job({}).windshield)
    np.testing.assert_allclose(model.pose, DEFAULT_WINDSHIELD.pose, atol=1e-12)
    moved = windshield_model(parse_job({"windshield": {"pose": {"xyz": [0.1, 0.4, 0.15],
                                                                "rpy": [math.radians(-55), 0, 0]}}}).windshield)
    p = DEFAULT_WINDSHIELD.surface_point(0.0, 0.2)
    np.testing.assert_allclose(moved.surface_point(0.0, 0.2), p + [0.1, 0.0, 0.0], atol=1e-12)


def test_seed_waypoints_with_the_seed_orientation():
    points, rots = job_waypoints(parse_job({}))
    np.testing.assert_allclose(points, DEFAULT_WAYPOINTS)
    np.testing.assert_allclose(rots, np.broadcast_to(rot_x(-math.pi / 3), (22, 3, 3)), atol=1e-12)


def test_standoff_lifts_the_seed_waypoints_along_the_glass_normal():
    points, _ = job_waypoints(parse_job({"standoff": 0.004}))
    _, foot, normal = DEFAULT_WINDSHIELD.project(points)
    height = np.sum((points - foot) * normal, axis=1)
    np.testing.assert_allclose(height, 0.004, atol=2e-4)  # the clicks lie within 0.1 mm of our glass
    np.testing.assert_allclose(np.linalg.norm(points - DEFAULT_WAYPOINTS, axis=1), 0.004, atol=1e-12)


@pytest.fixture(scope="module")
def auto():
    job = parse_job({"path": {"source": "auto", "inset": 0.03, "tilt_deg": 20.0, "point_spacing": 0.01},
                     "standoff": 0.002})
    return job, *job_waypoints(job)


def test_auto_points_lie_inset_and_above_the_glass(auto):
    _, points, _ = auto
    uv, foot, normal = DEFAULT_WINDSHIELD.project(points)
    np.testing.assert_allclose(np.sum((points - foot) * normal, axis=1), 0.002, atol=1e-9)
    np.testing.assert_allclose(DEFAULT_WINDSHIELD.edge_distance(uv), 0.03, atol=1e-6)
    gaps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert gaps.max() < 0.0105 and gaps.min() > 0.009  # the slope makes them a little longer


def test_auto_tool_axis_is_tilted_towards_the_robot(auto):
    _, points, rots = auto
    _, _, normal = DEFAULT_WINDSHIELD.project(points)
    nozzle = rots @ np.array([0.0, 1.0, 0.0])
    angle = np.degrees(np.arccos(np.clip(np.sum(-nozzle * normal, axis=1), -1, 1)))
    np.testing.assert_allclose(angle, 20.0, atol=1e-9)
    # the tool body (-nozzle) leans horizontally towards the base (the world z axis)
    lean = -nozzle - np.sum(-nozzle * normal, axis=1, keepdims=True) * normal
    towards_base = -points[:, :2]
    cos = np.sum(lean[:, :2] * towards_base, axis=1) / (np.linalg.norm(lean[:, :2], axis=1)
                                                         * np.linalg.norm(towards_base, axis=1))
    assert cos.min() > 0.9


def test_auto_roll_stays_near_the_reference(auto):
    job, _, rots = auto
    ref = rot_x(-math.pi / 3)
    # the smallest turn: the tip's x axis never turns about the nozzle away from the reference
    assert np.degrees(rotation_angle(rots, ref)).max() < 30.0
    assert np.all(np.linalg.det(rots) > 0.999)
    np.testing.assert_allclose(rots @ np.swapaxes(rots, 1, 2), np.broadcast_to(np.eye(3), rots.shape), atol=1e-12)


def test_align_axis_is_the_smallest_turn():
    ref = rot_z(0.3)
    d = np.array([0.0, 0.0, 1.0])
    out = align_axis(ref, np.array([1.0, 0.0, 0.0]), d)
    np.testing.assert_allclose(out @ [1.0, 0.0, 0.0], d, atol=1e-12)
    assert rotation_angle(out, ref) == pytest.approx(math.pi / 2)  # x tilts straight up: 90 deg
    with pytest.raises(ValueError, match="opposite"):
        align_axis(ref, np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]))
