"""passthrough.py: the passthrough controller's goal rules, the robot's interpolation and the end judgement."""
import numpy as np
import pytest

from ur_sim_driver.motion import result_codes as rc
from ur_sim_driver.motion.command_arrays import from_points
from ur_sim_driver.motion.passthrough import (
    NOT_WITHIN_TOLERANCE,
    PassthroughTolerances,
    check_goal,
    judge_end,
    robot_points,
    tolerances_of,
)
from ur_sim_driver.motion.trajectory import Trajectory
from ur_sim_driver.motion.trajectory_types import ToleranceSpec
from ur_sim_driver.motion.validation import map_to_config_order

JOINTS = ('a', 'b', 'c')


class P:
    def __init__(self, t, positions, velocities=(), accelerations=()):
        self.time_from_start = type('D', (), {'sec': int(t), 'nanosec': int(round((t - int(t)) * 1e9))})()
        self.positions, self.velocities, self.accelerations, self.effort = positions, velocities, accelerations, ()


def cmd(points, names=JOINTS):
    return from_points(names, 0.0, points)


def test_goal_rules():
    assert check_goal(cmd([P(1, [0, 0, 0]), P(2, [1, 1, 1])]), JOINTS, []) is None
    assert 'positions for all 3 joints' in check_goal(cmd([P(1, [0, 0])]), JOINTS, [])
    mixed = cmd([P(1, [0, 0, 0], [0, 0, 0]), P(2, [1, 1, 1])])
    assert 'velocities' in check_goal(mixed, JOINTS, [])
    mixed = cmd([P(1, [0, 0, 0], [0, 0, 0], [0, 0, 0]), P(2, [1, 1, 1], [0, 0, 0])])
    assert 'accelerations' in check_goal(mixed, JOINTS, [])
    ok = cmd([P(1, [0, 0, 0])])
    assert "joint 'x' given" in check_goal(ok, JOINTS, ['a', 'x'])
    assert 'Tolerances for 2 joints given. This controller knows 3 joints.' == check_goal(ok, JOINTS, ['a', 'b'])
    assert check_goal(ok, JOINTS, ['c', 'a', 'b']) is None


def test_tolerances_in_controller_order():
    tol = tolerances_of([ToleranceSpec('c', 3.0, 0.3), ToleranceSpec('a', 1.0, 0.1), ToleranceSpec('b', 2.0)],
                        JOINTS, 0.5)
    assert tol.position.tolist() == [1.0, 2.0, 3.0] and tol.velocity.tolist() == [0.1, 0.0, 0.3]
    assert tol.goal_time == 0.5
    empty = tolerances_of([], JOINTS, 0.0)
    assert empty.position is None and empty.velocity is None


def test_positions_only_stop_at_every_point_and_quintic_is_kept():
    points = map_to_config_order(cmd([P(1, [1, 0, 0]), P(2, [2, 0, 0])]), JOINTS, np.zeros(3))
    robot = robot_points(points)
    assert robot.has_velocities.all() and not robot.velocities.any()
    traj = Trajectory.start(robot, 0.0, np.zeros(3), np.zeros(3))
    # At rest at the intermediate point, moving between points (a cubic, not linear).
    assert np.allclose(traj.sample(1.0).velocities, 0.0)
    mid = traj.sample(1.5)
    assert mid.velocities[0] == pytest.approx(1.5)  # 3/2 x the mean speed in the middle of a cubic
    quintic = map_to_config_order(cmd([P(1, [1, 0, 0], [0.5, 0, 0], [0.1, 0, 0])]), JOINTS, np.zeros(3))
    kept = robot_points(quintic)
    assert kept.velocities[0, 0] == 0.5 and kept.accelerations[0, 0] == 0.1 and kept.has_accelerations.all()
    # Accelerations without velocities: positions only.
    odd = map_to_config_order(cmd([P(1, [1, 0, 0], (), [3, 3, 3])]), JOINTS, np.zeros(3))
    assert not robot_points(odd).accelerations.any() and not robot_points(odd).velocities.any()


def test_end_judgement():
    final = np.array([1.0, 2.0, 3.0])
    q = final + 0.005
    tol = PassthroughTolerances(np.full(3, 0.01), np.zeros(3), 1.0)
    code, text = judge_end(q, np.zeros(3), final, None, tol, 12.002, 12.0)
    assert code == rc.SUCCESSFUL and 'executed successfully in 12.002000 (scaled) seconds' in text
    tight = PassthroughTolerances(np.full(3, 1e-9), np.zeros(3), 1.0)
    assert judge_end(q, np.zeros(3), final, None, tight, 12.002, 12.0) == (rc.GOAL_TOLERANCE_VIOLATED,
                                                                          NOT_WITHIN_TOLERANCE)
    # Velocity is judged only where the last point gave velocities.
    moving = np.full(3, 0.02)
    velocity_tol = PassthroughTolerances(np.full(3, 0.01), np.full(3, 0.01), 1.0)
    assert judge_end(q, moving, final, None, velocity_tol, 12.0, 12.0)[0] == rc.SUCCESSFUL
    assert judge_end(q, moving, final, np.zeros(3), velocity_tol, 12.0, 12.0)[0] == rc.GOAL_TOLERANCE_VIOLATED
    late = PassthroughTolerances(np.full(3, 0.01), np.zeros(3), 1e-8)
    code, text = judge_end(q, np.zeros(3), final, None, late, 12.002, 12.0)
    assert code == rc.GOAL_TOLERANCE_VIOLATED and text.startswith('Goal not reached within time tolerance.')
    # No goal tolerance: nothing but time is judged; goal_time_tolerance 0: time is not judged.
    assert judge_end(q + 5, np.zeros(3), final, None, PassthroughTolerances(None, None, 0.0), 99.0, 12.0)[0] == \
        rc.SUCCESSFUL
