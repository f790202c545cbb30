"""Glue job files: the default job is seed 1's, and every bad field is named."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from ur_glue_planner.defaults import DEFAULT_WAYPOINTS
from ur_glue_planner.errors import JobError
from ur_glue_planner.job import GlueJob, default_job_path, load_job, parse_job

JOB_FILE = Path(__file__).resolve().parents[1] / "config" / "glue_job.yaml"


@pytest.fixture(scope="module")
def job() -> GlueJob:
    return load_job(JOB_FILE)


def test_default_job_is_seed_1(job):
    assert job.ur_type == "ur5" and job.tool == "dispenser"
    assert job.path.source == "waypoints" and job.path.closed
    np.testing.assert_allclose(job.path.waypoints, DEFAULT_WAYPOINTS)
    assert len(job.path.waypoints) == 22
    np.testing.assert_allclose(job.path.orientation_zyx, [[0.0, 0.0, -math.pi / 3]])
    assert job.tcp_speed == 0.15 and job.sample_time == 0.02
    assert job.approach_min_duration == 4.0 and job.standoff == 0.0
    np.testing.assert_allclose(job.home, np.radians([0, -90, 0, -90, 0, 0]))
    assert job.ik_seed is None
    assert job.windshield.xyz == (0.0, 0.4, 0.15)
    assert job.windshield.rpy[0] == pytest.approx(math.radians(-55.0))
    assert job.controller_name == "scaled_joint_trajectory_controller" and job.namespace == ""
    assert job.tolerances.goal_position == (0.01,) * 6 and len(job.tolerances.path_position) == 6
    assert job.source_file == str(JOB_FILE)


def test_default_job_path_is_the_source_tree_file():
    assert default_job_path() == JOB_FILE


def test_missing_keys_take_the_documented_defaults(job):
    # the file spells out every default: an empty job must equal it
    empty = parse_job({})
    assert empty == parse_job(yaml.safe_load(JOB_FILE.read_text()))
    assert empty.path == job.path and empty.tcp_speed == job.tcp_speed


def test_job_is_frozen(job):
    with pytest.raises(AttributeError):
        job.tcp_speed = 1.0  # type: ignore[misc]


@pytest.mark.parametrize("raw, field, hint", [
    ({"ur_type": "ur6"}, "ur_type", "ur3, ur3e, ur5, ur5e, ur7e, ur8long"),
    ({"tool": "gripper"}, "tool", "dispenser"),
    ({"tcp_speed": 0}, "tcp_speed", "(0, 1]"),
    ({"tcp_speed": "fast"}, "tcp_speed", "(0, 1]"),
    ({"tcp_speed": True}, "tcp_speed", "(0, 1]"),
    ({"sample_time": 0.5}, "sample_time", "[0.001, 0.1]"),
    ({"standoff": -0.001}, "standoff", "[0, 0.05]"),
    ({"approach_velocity_scale": 1.5}, "approach_velocity_scale", "(0, 1]"),
    ({"path": {"source": "spline"}}, "path.source", "waypoints, auto"),
    ({"path": {"inset": 0.5}}, "path.inset", "[0, 0.2]"),
    ({"path": {"tilt_deg": 75}}, "path.tilt_deg", "[0, 60]"),
    ({"path": {"corner_max_deviation": 0}}, "path.corner_max_deviation", "(0, 0.1]"),
    ({"path": {"closed": "yes"}}, "path.closed", "true or false"),
    ({"path": {"waypoints": [[0, 0, 0]]}}, "path.waypoints", "at least 2"),
    ({"path": {"waypoints": [[0, 0], [1, 1]]}}, "path.waypoints", "[x, y, z]"),
    ({"path": {"waypoints": [[0, 0, 0], [400, 0, 0]]}}, "path.waypoints", "metres"),
    ({"path": {"orientation_zyx": [0, 0]}}, "path.orientation_zyx", "(22, 3)"),
    ({"windshield": {"pose": {"xyz": [0, 0.4]}}}, "windshield.pose.xyz", "[x, y, z]"),
    ({"windshield": {"mesh": ""}}, "windshield.mesh", "non-empty"),
    ({"home_deg": [0, 0, 0]}, "home_deg", "6 joint angles"),
    ({"ik_seed_deg": [0, 0, 0, 0, 0, 720]}, "ik_seed_deg", "[-360, 360]"),
    ({"tolerances": {"goal_position": -0.1}}, "tolerances.goal_position", "(0, 3.1416]"),
    ({"tolerances": {"goal_time_tolerance": -1}}, "tolerances.goal_time_tolerance", "[0, 60]"),
    ({"namespace": "ur10"}, "namespace", "start with '/'"),
    ({"tcp_sped": 0.1}, "tcp_sped", "unknown key"),
    ({"path": {"tilt": 10}}, "path.tilt", "unknown key"),
])
def test_invalid_fields_are_named_with_value_and_range(raw, field, hint):
    with pytest.raises(JobError) as err:
        parse_job(raw)
    message = str(err.value)
    assert message.startswith(f"{field}:"), message
    assert hint in message


def test_value_appears_in_the_message():
    with pytest.raises(JobError, match=r"path\.inset: 0\.25 is not a number in \[0, 0\.2\]"):
        parse_job({"path": {"inset": 0.25}})


def test_orientation_per_waypoint_and_ik_seed_in_degrees():
    job = parse_job({"path": {"waypoints": [[0.3, 0.4, 0.2], [0.3, 0.5, 0.2]],
                              "orientation_zyx": [[0, 0, -1.0], [0, 0, -1.1]]},
                     "ik_seed_deg": [0, -90, 90, 0, 90, 0]})
    assert job.path.orientation_zyx == ((0.0, 0.0, -1.0), (0.0, 0.0, -1.1))
    np.testing.assert_allclose(job.ik_seed, [0, -math.pi / 2, math.pi / 2, 0, math.pi / 2, 0])


def test_unreadable_files_raise_job_error(tmp_path):
    with pytest.raises(JobError, match="cannot read glue job"):
        load_job(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("ur_type: [ur5\n")
    with pytest.raises(JobError, match="cannot read glue job"):
        load_job(bad)
    bad.write_text("- just a list\n")
    with pytest.raises(JobError, match="job: must be a mapping"):
        load_job(bad)


def test_dispenser_defaults_are_ur_sims(job):
    d = job.dispenser
    assert (d.pin, d.flow_rate, d.nozzle_diameter) == (16, 6.0, 6.0)
    assert (d.on_delay, d.off_delay, d.time_constant) == (0.05, 0.03, 0.05)
    assert d.flying_start and d.kind == "tool" and job.method == "constant_speed"


@pytest.mark.parametrize("raw, field, hint", [
    ({"dispenser": {"pin": 18}}, "dispenser.pin", "18 is not a digital output pin in [0, 17]"),
    ({"dispenser": {"pin": True}}, "dispenser.pin", "True is not a digital output pin in [0, 17]"),
    ({"dispenser": {"flow_rate": 0}}, "dispenser.flow_rate", "0 is not a number in (0, 100]"),
    ({"dispenser": {"on_delay": -0.1}}, "dispenser.on_delay", "-0.1 is not a number in [0, 2]"),
    ({"dispenser": {"off_delay": 3}}, "dispenser.off_delay", "3 is not a number in [0, 2]"),
    ({"dispenser": {"time_constant": 2}}, "dispenser.time_constant", "2 is not a number in [0, 1]"),
    ({"dispenser": {"nozzle": 6}}, "dispenser.nozzle", "unknown key; allowed: flow_rate"),
    ({"method": "fast"}, "method", "'fast' is not one of: constant_speed, seed1"),
])
def test_bad_dispenser_and_method_fields_are_named(raw, field, hint):
    with pytest.raises(JobError) as err:
        parse_job(raw)
    assert str(err.value).startswith(field) and hint in str(err.value)
