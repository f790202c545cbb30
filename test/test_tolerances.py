"""Tests of ur_sim_driver.motion.tolerances: defaults, per-goal overrides, checks and outcomes."""

import math

import numpy as np
import pytest

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.tolerances import (
    check_goal,
    check_path,
    check_state_tolerance,
    default_tolerances,
    goal_outcome,
    resolve_tolerances,
    resolve_value,
)
from ur_sim_driver.motion.trajectory_types import JointTolerances, ToleranceSpec

JOINTS = ("j0", "j1", "j2")


def ur_defaults(goal_time=0.0):
    # UR driver config: trajectory 0.2, goal 0.1, stopped_velocity_tolerance 0.2.
    return default_tolerances(JOINTS, trajectory=0.2, goal=0.1, stopped_velocity=0.2, goal_time=goal_time)


def test_defaults_from_constraints():
    tol = ur_defaults()
    np.testing.assert_allclose(tol.path.position, [0.2] * 3)
    np.testing.assert_allclose(tol.path.velocity, 0.0)
    np.testing.assert_allclose(tol.goal.position, [0.1] * 3)
    np.testing.assert_allclose(tol.goal.velocity, [0.2] * 3)  # stopped_velocity_tolerance
    np.testing.assert_allclose(tol.goal.acceleration, 0.0)
    assert tol.goal_time == 0.0


def test_defaults_per_joint_lists():
    tol = default_tolerances(JOINTS, trajectory=[0.1, 0.2, 0.3], goal=0.0, stopped_velocity=0.01, goal_time=0.5)
    np.testing.assert_allclose(tol.path.position, [0.1, 0.2, 0.3])
    assert tol.goal_time == 0.5


@pytest.mark.parametrize(
    "kwargs, word",
    [
        ({"trajectory": [0.1, 0.2]}, "trajectory"),
        ({"goal": -0.1}, "goal"),
        ({"stopped_velocity": -1.0}, "stopped_velocity"),
        ({"goal_time": math.nan}, "goal_time"),
    ],
)
def test_bad_defaults_raise_config_error(kwargs, word):
    args = {"trajectory": 0.2, "goal": 0.1, "stopped_velocity": 0.2, "goal_time": 0.0}
    args.update(kwargs)
    with pytest.raises(ConfigError, match=word):
        default_tolerances(JOINTS, **args)


@pytest.mark.parametrize(
    "requested, expected",
    [(0.5, 0.5), (0.0, 0.3), (-1.0, 0.0), (-1.0 + 1e-9, 0.0), (-2.0, None), (-0.5, None), (math.nan, None)],
)
def test_resolve_value_rules(requested, expected):
    assert resolve_value(0.3, requested) == expected


def test_path_override_positive_zero_and_erase():
    specs = [ToleranceSpec("j0", position=0.5, velocity=1.0), ToleranceSpec("j2", position=-1.0)]
    tol, reason = resolve_tolerances(ur_defaults(), JOINTS, path_overrides=specs)
    assert reason is None
    np.testing.assert_allclose(tol.path.position, [0.5, 0.2, 0.0])
    np.testing.assert_allclose(tol.path.velocity, [1.0, 0.0, 0.0])
    np.testing.assert_allclose(tol.goal.position, [0.1] * 3)  # goal untouched


def test_goal_override_replaces_stopped_velocity():
    specs = [ToleranceSpec("j1", position=0.0, velocity=0.05), ToleranceSpec("j2", velocity=-1)]
    tol, reason = resolve_tolerances(ur_defaults(), JOINTS, goal_overrides=specs)
    assert reason is None
    np.testing.assert_allclose(tol.goal.position, [0.1] * 3)
    np.testing.assert_allclose(tol.goal.velocity, [0.2, 0.05, 0.0])


@pytest.mark.parametrize("requested, expected", [(0.0, 0.7), (0.01, 0.01), (-1.0, 0.0)])
def test_goal_time_tolerance_rules(requested, expected):
    tol, reason = resolve_tolerances(ur_defaults(goal_time=0.7), JOINTS, goal_time_tolerance=requested)
    assert reason is None and tol.goal_time == pytest.approx(expected)


def test_unknown_joint_falls_back_to_defaults_with_reason():
    defaults = ur_defaults()
    specs = [ToleranceSpec("j0", position=0.9), ToleranceSpec("ghost", position=0.9)]
    tol, reason = resolve_tolerances(defaults, JOINTS, goal_overrides=specs)
    assert tol is defaults
    assert "goal_tolerance" in reason and "'ghost'" in reason


def test_illegal_value_falls_back_to_defaults_with_reason():
    defaults = ur_defaults()
    specs = [ToleranceSpec("j1", acceleration=-3.0)]
    tol, reason = resolve_tolerances(defaults, JOINTS, path_overrides=specs, goal_time_tolerance=2.0)
    assert tol is defaults and tol.goal_time == 0.0
    assert "path_tolerance[j1].acceleration" in reason and "-3" in reason


def test_illegal_goal_time_tolerance():
    tol, reason = resolve_tolerances(ur_defaults(), JOINTS, goal_time_tolerance=-0.5)
    assert "goal_time_tolerance" in reason and "-0.5" in reason


def test_state_within_tolerance_passes():
    tol = JointTolerances(np.full(3, 0.1), np.full(3, 0.5), np.zeros(3))
    assert check_state_tolerance(np.array([0.1, -0.1, 0.05]), np.zeros(3), None, tol, JOINTS) is None


def test_state_violation_names_joint_error_and_tolerance():
    tol = JointTolerances(np.full(3, 0.1), np.full(3, 0.5), np.zeros(3))
    reason = check_state_tolerance(np.array([0.0, -0.25, 0.0]), None, None, tol, JOINTS, "path")
    assert reason.startswith("path tolerance violated")
    assert "j1" in reason and "position" in reason and "-0.25" in reason and "0.1" in reason
    reason = check_state_tolerance(np.zeros(3), np.array([0, 0, 0.6]), None, tol, JOINTS)
    assert "j2" in reason and "velocity" in reason and "0.6" in reason


def test_zero_tolerance_is_not_checked():
    tol = JointTolerances.unchecked(3)
    assert check_state_tolerance(np.full(3, 50.0), np.full(3, 50.0), np.full(3, 50.0), tol, JOINTS) is None


def test_non_finite_error_fails_where_checked():
    tol = JointTolerances(np.full(3, 0.1), np.zeros(3), np.zeros(3))
    assert "j0" in check_state_tolerance(np.array([math.nan, 0, 0]), None, None, tol, JOINTS)


def test_goal_check_uses_stopped_velocity():
    tol = ur_defaults()
    pos_ok = np.array([0.05, 0.0, 0.0])
    assert check_goal(pos_ok, np.array([0.1, 0.0, 0.0]), None, tol, JOINTS) is None
    reason = check_goal(pos_ok, np.array([0.0, 0.3, 0.0]), None, tol, JOINTS)
    assert reason.startswith("goal tolerance") and "j1" in reason and "velocity" in reason
    assert check_path(np.array([0.15, 0, 0]), np.array([9.0] * 3), None, tol, JOINTS) is None


def test_goal_outcome_success_at_end():
    assert goal_outcome(-0.01, None, 0.0) is None  # still running
    assert goal_outcome(0.0, None, 0.0) == result_codes.SUCCESSFUL


def test_goal_outcome_waits_forever_with_zero_goal_time():
    assert goal_outcome(1e6, "goal tolerance violated: ...", 0.0) is None


def test_goal_outcome_times_out_after_goal_time():
    reason = "goal tolerance violated: ..."
    assert goal_outcome(0.3, reason, 0.5) is None
    assert goal_outcome(0.5, reason, 0.5) is None  # upstream: strictly greater
    assert goal_outcome(0.51, reason, 0.5) == result_codes.GOAL_TOLERANCE_VIOLATED
    assert goal_outcome(0.51, None, 0.5) == result_codes.SUCCESSFUL


def test_result_codes_match_control_msgs():
    assert (
        result_codes.SUCCESSFUL,
        result_codes.INVALID_GOAL,
        result_codes.INVALID_JOINTS,
        result_codes.OLD_HEADER_TIMESTAMP,
        result_codes.PATH_TOLERANCE_VIOLATED,
        result_codes.GOAL_TOLERANCE_VIOLATED,
    ) == (0, -1, -2, -3, -4, -5)
