"""The per-cycle logic of a scaled joint trajectory controller (JTC), without ROS.

One instance owns the active trajectory and decides, every control cycle, the reference the low-level
controller tracks and whether the active goal has ended. It reproduces ros2_controllers'
joint_trajectory_controller as the UR driver configures it (``scaled_joint_trajectory_controller``):

* trajectory time advances by ``period x speed_scaling_input x the robot's own factor``
  (``speed_scaling.py``: the emulated robot slows itself where it cannot follow); an input of 0 pauses;
* the reference it returns is in real time: velocities and accelerations are multiplied by that factor
  (and its square), so the robot's servo and torque controller see the motion actually asked of them;
* a new trajectory replaces the active one; an action goal that is replaced ends with INVALID_GOAL
  "Current goal preempted by new incoming action." (upstream); replaced by a topic message it ends the
  same way with its own message (upstream leaves such a goal running against the topic's trajectory,
  which then reports on a motion it did not ask for; we end it instead, as a user expects);
* while running, and on the first sample even when that is already the last point (upstream: "in case
  the first sample is the last point"), the path tolerance is checked for action goals; a violation
  aborts with PATH_TOLERANCE_VIOLATED and holds the measured position;
* after the last point, the goal tolerance (position, and velocity against
  ``stopped_velocity_tolerance``) decides SUCCESSFUL, or GOAL_TOLERANCE_VIOLATED once ``goal_time`` has
  passed (0 = wait without limit, as upstream); after success the last point is held;
* cancel holds the measured position.
"""
from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass

import numpy as np

from ur_sim_driver.motion import result_codes
from ur_sim_driver.motion.tolerances import check_goal, check_path, goal_outcome
from ur_sim_driver.motion.trajectory import Trajectory, TrajectorySample
from ur_sim_driver.motion.trajectory_types import SegmentTolerances, TrajectoryPoints
from ur_sim_driver.robot.speed_scaling import RobotSpeedScaling

# Upstream JTC's words while it is inactive (goals; topic messages).
INACTIVE_GOAL = "Can't accept new action goals. Controller is not running."
INACTIVE_TOPIC = "Can't accept new commands. subscriber is inactive"
PREEMPTED_BY_ACTION = 'Current goal preempted by new incoming action.'
PREEMPTED_BY_TOPIC = 'Current goal preempted by a new trajectory on the joint_trajectory topic.'


@dataclass(frozen=True)
class Outcome:
    """How an action goal ended.

    Attributes:
        token: the goal's token as given to :meth:`TrajectoryController.start`.
        code: control_msgs FollowJointTrajectory result code.
        message: error_string ('' on success).
    """

    token: Hashable
    code: int
    message: str


class TrajectoryController:
    """Reference generation and goal supervision, one call of :meth:`update` per control cycle.

    Args:
        joint_names: n controller joint names.
        defaults: default tolerances (from the ``constraints`` parameters).
        hold_positions: (n,) [rad] position held before any trajectory.
        v_max, a_max: (n,) joint velocity [rad/s] and acceleration [rad/s^2] limits of the robot.
        speed_scaling: initial speed_scaling_input factor in [0, 1].
        scaling: the robot's own speed scaling, shared by every controller that commands the robot (a new one
            when None).
        scaled: advance trajectory time by the speed scaling (the scaled JTC); False ignores it
            (joint_trajectory_controller): trajectory time is real time, whatever the robot makes of it.

    Attributes:
        speed_scaling: the speed_scaling_input factor in [0, 1] (set by the node).
        scaling: the robot's own speed scaling, updated every cycle.
        stop: (n,) [rad] position the robot must not pass this cycle (the final point while the last
            segment runs, or the hold position), or None.
    """

    def __init__(self, joint_names: tuple[str, ...], defaults: SegmentTolerances,
                 hold_positions: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                 speed_scaling: float = 1.0, scaling: RobotSpeedScaling | None = None,
                 scaled: bool = True) -> None:
        self.joint_names = tuple(joint_names)
        self.defaults = defaults
        self.speed_scaling = float(speed_scaling)
        self.scaling = scaling if scaling is not None else RobotSpeedScaling(v_max, a_max, speed_scaling)
        self.scaled = scaled
        self.stop: np.ndarray | None = np.array(hold_positions, dtype=float)
        self._first_sample = False
        self._hold = np.array(hold_positions, dtype=float)
        self._hold_cached: TrajectorySample | None = None
        self._trajectory: Trajectory | None = None
        self._tolerances: SegmentTolerances | None = None
        self._token: Hashable | None = None
        self._traj_time = 0.0
        self.last_sample: TrajectorySample | None = None

    @property
    def active_token(self) -> Hashable | None:
        """Token of the action goal being executed, or None (idle, holding, or a topic trajectory)."""
        return self._token

    @property
    def trajectory(self) -> Trajectory | None:
        """The trajectory being executed, or None while holding."""
        return self._trajectory

    @property
    def trajectory_time(self) -> float:
        """Scaled trajectory time [s]: advances by period x speed scaling factor."""
        return self._traj_time

    def start(self, points: TrajectoryPoints, now: float, q: np.ndarray, qd: np.ndarray,
              token: Hashable | None = None, tolerances: SegmentTolerances | None = None) -> Outcome | None:
        """Replace the active trajectory.

        Args:
            points: validated trajectory in controller order.
            now: current time [s].
            q, qd: (n,) measured state [rad], [rad/s]; the first segment starts from it.
            token: identifies an action goal; None for a topic message (no tolerance supervision).
            tolerances: resolved tolerances of the goal (defaults when None).

        Returns:
            The outcome of the action goal this one preempts, if any.
        """
        preempted = None
        if self._token is not None:
            message = PREEMPTED_BY_ACTION if token is not None else PREEMPTED_BY_TOPIC
            preempted = Outcome(self._token, result_codes.INVALID_GOAL, message)
        self._traj_time = now
        self._trajectory = Trajectory.start(points, now, q, qd)
        self._tolerances = tolerances if tolerances is not None else self.defaults
        self._token = token
        self._first_sample = True
        return preempted

    def cancel(self, token: Hashable, q: np.ndarray) -> bool:
        """Cancel the action goal `token` if it is active and hold the measured position `q` (n,) [rad]."""
        if token is None or token != self._token:
            return False
        self.hold(q)
        return True

    def hold(self, q: np.ndarray) -> None:
        """Drop any trajectory (ending no goal) and hold position `q` (n,) [rad]."""
        self._trajectory = None
        self._token = None
        self._hold = np.array(q, dtype=float)

    def update(self, now: float, period: float, q: np.ndarray, qd: np.ndarray) -> tuple[TrajectorySample,
                                                                                         Outcome | None]:
        """Advance one control cycle.

        Args:
            now: time at the start of this cycle [s].
            period: control period since the last cycle [s].
            q, qd: (n,) measured state [rad], [rad/s].

        Returns:
            (reference, outcome): the reference to track now, and the outcome of the active goal if it
            ended in this cycle.
        """
        outcome = None
        traj = self._trajectory
        if traj is None:
            raw = self._hold_sample()
            # Holding, nothing moves or lags: the scaling's update for a reference at rest.
            self.scaling.update_at_rest(self.speed_scaling, period)
            self.stop = self._hold
            sample = raw
        else:
            # Sample at the current trajectory time, then advance it (as upstream): the reference for this
            # cycle is the trajectory at `now`, which the joint controller tracks at this instant.
            t_sample = self._traj_time
            raw = traj.sample(t_sample)
            last = len(traj.points.times) - 1
            self.stop = traj.points.positions[last] if raw.ended or raw.segment_index == last else None
            # The factor read this cycle is the robot's from the previous one (the driver reads it with the
            # state); what the robot makes of this cycle's reference shows from the next cycle on.
            total = self.scaling.total if self.scaled else 1.0
            self.scaling.update(raw.velocities, raw.positions - q, self.speed_scaling, period)
            sample = raw._replace(velocities=raw.velocities * total, accelerations=raw.accelerations * total**2)
            self._traj_time += period * total
            if self._token is not None:
                outcome = self._supervise(sample, t_sample - traj.end_time, q, qd)
            self._first_sample = False
            if outcome is None and sample.ended and self._token is None:
                # Topic trajectories (and finished goals) end by holding their last point.
                self.hold(sample.positions)
        self.last_sample = sample
        return sample, outcome

    def _supervise(self, sample: TrajectorySample, time_since_end: float, q: np.ndarray,
                   qd: np.ndarray) -> Outcome | None:
        tol = self._tolerances
        err_q = sample.positions - q
        err_qd = sample.velocities - qd
        token = self._token
        if not sample.ended or self._first_sample:
            reason = check_path(err_q, err_qd, None, tol, self.joint_names)
            if reason is not None:
                self.hold(q)
                return Outcome(token, result_codes.PATH_TOLERANCE_VIOLATED, reason)
            if not sample.ended:
                return None
        # Past the end the goal state is the last point at rest: velocity is judged against 0.
        reason = check_goal(err_q, -qd, None, tol, self.joint_names)
        code = goal_outcome(time_since_end, reason, tol.goal_time)
        if code is None:
            return None
        if code == result_codes.SUCCESSFUL:
            self.hold(sample.positions)
            return Outcome(token, code, '')
        self.hold(q)
        return Outcome(token, code, f'{reason} after goal_time {tol.goal_time:.3f} s')

    def _hold_sample(self) -> TrajectorySample:
        """The sample of the held position, built once per hold: read-only arrays, shared by every cycle."""
        cached = self._hold_cached
        if cached is None or cached.positions.base is not self._hold:
            n = len(self._hold)
            arrays = self._hold[:], np.zeros(n), np.zeros(n)  # a view: its base tells which hold it belongs to
            for a in arrays:
                a.flags.writeable = False
            cached = self._hold_cached = TrajectorySample(*arrays, 0, True)
        return cached
