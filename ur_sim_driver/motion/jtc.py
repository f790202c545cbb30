"""The per-cycle logic of a scaled joint trajectory controller (JTC), without ROS.

One instance owns the active trajectory and decides, every control cycle, the reference the low-level
controller tracks and whether the active goal has ended. It reproduces ros2_controllers'
joint_trajectory_controller (jazzy, 4.39 or later) as the UR driver configures it, and the driver's
``scaled_joint_trajectory_controller`` (``scaled=True``):

* trajectory time advances by ``period x factor`` (upstream ``update``: ``traj_time_ += period * scaling_factor_``).
  The scaled controller's factor is the hardware's ``speed_scaling/speed_scaling_factor``: the robot's speed scaling
  (``speed_scaling.py``: slider x the robot's own slowdown where it cannot follow). The plain controller's is its
  own: ``speed_scaling.initial_scaling_factor``, then each ``~/speed_scaling_input`` (any factor >= 0; 0 pauses,
  above 1 speeds up; applied at once, as upstream). The scaled controller has that input too (it inherits it) but
  its motion does not follow it: it reads the hardware's factor every cycle into a member of its own;
* the reference it returns is in real time: velocities and accelerations are multiplied by that factor
  (and its square), so the robot's servo and torque controller see the motion actually asked of them;
* a new trajectory replaces the active one; an action goal that is replaced ends with INVALID_GOAL
  "Current goal preempted by new incoming action." (upstream); replaced by a topic message it ends the
  same way with its own message (upstream leaves such a goal running against the topic's trajectory,
  which then reports on a motion it did not ask for; we end it instead, as a user expects);
* while running, and on the first sample even when that is already the last point (upstream: "in case
  the first sample is the last point"), the path tolerance is checked; a violation holds the measured position
  and aborts an action goal with PATH_TOLERANCE_VIOLATED "Aborted due to path tolerance violation" (a topic
  trajectory, checked against the default tolerances, is held: "Holding position due to state tolerance
  violation"); success reads "Goal successfully reached!" and a missed goal time "Aborted due to
  goal_time_tolerance exceeding by <s> seconds" (upstream's words; which joint failed goes to the log);
* after the last point, the goal tolerance decides SUCCESSFUL, or GOAL_TOLERANCE_VIOLATED once ``goal_time`` has
  passed (0 = wait without limit, as upstream); after success the last point is held;
* velocity errors are checked (path and goal tolerances, ``stopped_velocity_tolerance``) only where the controller
  commands velocity or effort (upstream ``compute_error_for_joint``: a velocity error exists only with a velocity
  state interface and a velocity or effort command interface). The driver's JTCs command position only
  (``ur_controllers.yaml``), so their velocity tolerances are never checked: ``velocity_errors`` is False;
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
# The result's error_string and the log's words (ur_controllers' scaled_joint_trajectory_controller.cpp update()).
GOAL_REACHED = 'Goal successfully reached!'
PATH_ABORTED = 'Aborted due to path tolerance violation'
TOPIC_PATH_HOLD = 'Holding position due to state tolerance violation'
TOPIC_GOAL_TIME_HOLD = 'Exceeded goal_time_tolerance: holding position...'


def goal_time_aborted(time_since_end: float) -> str:
    """The error_string of a goal that missed its goal time: `time_since_end` [s] past the last point."""
    return f'Aborted due to goal_time_tolerance exceeding by {time_since_end:.6f} seconds'


@dataclass(frozen=True)
class Outcome:
    """How an action goal ended.

    Attributes:
        token: the goal's token as given to :meth:`TrajectoryController.start`; None for a topic trajectory the
            controller stopped (held) on its tolerances.
        code: control_msgs FollowJointTrajectory result code.
        message: error_string, upstream's words.
        detail: which joint left which tolerance by how much, for the log ('' when none).
    """

    token: Hashable | None
    code: int
    message: str
    detail: str = ''


class TrajectoryController:
    """Reference generation and goal supervision, one call of :meth:`update` per control cycle.

    Args:
        joint_names: n controller joint names.
        defaults: default tolerances (from the ``constraints`` parameters).
        hold_positions: (n,) [rad] position held before any trajectory.
        v_max, a_max: (n,) joint velocity [rad/s] and acceleration [rad/s^2] limits of the robot.
        speed_scaling: the controller's own initial factor (``speed_scaling.initial_scaling_factor``), >= 0.
        scaling: the robot's own speed scaling, shared by every controller that commands the robot (a new one
            when None).
        scaled: advance trajectory time by the robot's speed scaling (the scaled JTC); False: by the controller's
            own factor (joint_trajectory_controller), whatever the robot makes of it.

    Attributes:
        speed_scaling: the controller's own factor, >= 0 (``~/speed_scaling_input``, set by the node; what its
            controller_state reports, in the scaled controller too).
        scaling: the robot's own speed scaling, updated every cycle.
        stop: (n,) [rad] position the robot must not pass this cycle (the final point while the last
            segment runs, or the hold position), or None.
    """

    def __init__(self, joint_names: tuple[str, ...], defaults: SegmentTolerances,
                 hold_positions: np.ndarray, v_max: np.ndarray, a_max: np.ndarray,
                 speed_scaling: float = 1.0, scaling: RobotSpeedScaling | None = None,
                 scaled: bool = True, velocity_errors: bool = False) -> None:
        self.joint_names = tuple(joint_names)
        self.velocity_errors = velocity_errors  # a velocity or effort command interface (the UR config: none)
        self.defaults = defaults
        self.speed_scaling = float(speed_scaling)
        self.scaling = scaling if scaling is not None else RobotSpeedScaling(v_max, a_max)
        self.scaled = scaled
        self.stop: np.ndarray | None = np.array(hold_positions, dtype=float)
        self._first_sample = False
        self._hold = np.array(hold_positions, dtype=float)
        self._hold_cached: TrajectorySample | None = None
        self._trajectory: Trajectory | None = None
        self._tolerances: SegmentTolerances | None = None
        self._token: Hashable | None = None
        self._traj_time = 0.0
        self._t_sample: float | None = None  # trajectory time of this cycle's sample (None while holding)
        self.last_sample: TrajectorySample | None = None
        self.desired: TrajectorySample | None = None  # this cycle's sample in trajectory time (not scaled)
        # (reference, feedback) time_from_start [s] of this cycle, as upstream's controller_state has them: trajectory
        # time and time since the trajectory's start. Holding is upstream's one-point hold trajectory from then on.
        self.time_from_start = (0.0, 0.0)
        self._hold_since: float | None = None  # [s] when the current hold started (None: not holding yet)
        self._hold_time = 0.0  # [s] trajectory time of the hold

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
            token: identifies an action goal; None for a topic message (held on its default tolerances).
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
        self._hold_since = None

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
            self.scaling.update_at_rest(period)
            self.stop = self._hold
            self._t_sample = None
            if self._hold_since is None:
                self._hold_since, self._hold_time = now, 0.0
            else:
                self._hold_time += period * (self.scaling.factor if self.scaled else self.speed_scaling)
            self.time_from_start = (self._hold_time, now - self._hold_since)
            sample = raw
        else:
            # Sample at the current trajectory time, then advance it (as upstream): the reference for this
            # cycle is the trajectory at `now`, which the joint controller tracks at this instant.
            t_sample = self._t_sample = self._traj_time
            raw = traj.sample(t_sample)
            self.time_from_start = (t_sample - traj.start_time, now - traj.start_time)
            last = len(traj.points.times) - 1
            self.stop = traj.points.positions[last] if raw.ended or raw.segment_index == last else None
            # The robot's factor read this cycle is the one of the previous cycle (the driver reads it with the
            # state); what the robot makes of this cycle's reference shows from the next cycle on.
            if self.scaled:
                total = self.scaling.factor
                self.scaling.update(raw.velocities, raw.positions - q, period)
            else:
                total = self.speed_scaling
                self.scaling.update(raw.velocities * total, raw.positions - q, period)
            sample = raw._replace(velocities=raw.velocities * total, accelerations=raw.accelerations * total**2)
            self._traj_time += period * total
            # Action goals and topic trajectories alike (the topic's with the default tolerances).
            outcome = self._supervise(sample, t_sample - traj.end_time, q, qd)
            self._first_sample = False
        self.last_sample = sample
        self.desired = raw
        return sample, outcome

    def command_positions(self, update_period: float) -> np.ndarray:
        """(n,) [rad] what upstream writes to the position command interfaces this cycle (``command_next_``): the
        trajectory at this cycle's trajectory time plus one update period (not scaled), or the held position. Call
        after :meth:`update`, under the same lock. The robot here tracks the trajectory itself through the period
        (``desired`` at the cycle's start, with velocity and acceleration), which brings the arm to the same place
        at the period's end as a robot that reaches the command then."""
        traj = self._trajectory
        if traj is None or self._t_sample is None:
            return self._hold
        return traj.sample(self._t_sample + update_period).positions

    def _supervise(self, sample: TrajectorySample, time_since_end: float, q: np.ndarray,
                   qd: np.ndarray) -> Outcome | None:
        """Upstream's checks each cycle: a path tolerance violation (while moving, and on the first sample) holds
        the measured position; past the last point, the goal tolerance ends the goal (success: the last point is
        held) or, after goal_time, holds the measured position. A topic trajectory (no token) is held the same
        way, with no result to send: the outcome then only carries what to log."""
        tol = self._tolerances
        err_q = sample.positions - q
        err_qd = sample.velocities - qd if self.velocity_errors else None
        token = self._token
        if not sample.ended or self._first_sample:
            reason = check_path(err_q, err_qd, None, tol, self.joint_names)
            if reason is not None:
                self.hold(q)
                return Outcome(token, result_codes.PATH_TOLERANCE_VIOLATED,
                               PATH_ABORTED if token is not None else TOPIC_PATH_HOLD, reason)
            if not sample.ended:
                return None
        # Past the end the goal state is the last point at rest: velocity (where checked) is judged against 0.
        reason = check_goal(err_q, -qd if self.velocity_errors else None, None, tol, self.joint_names)
        code = goal_outcome(time_since_end, reason, tol.goal_time)
        if code is None:
            return None
        if code == result_codes.SUCCESSFUL:
            self.hold(sample.positions)
            return Outcome(token, code, GOAL_REACHED) if token is not None else None
        self.hold(q)
        message = goal_time_aborted(time_since_end) if token is not None else TOPIC_GOAL_TIME_HOLD
        return Outcome(token, code, message, f'{reason} after goal_time {tol.goal_time:.3f} s')

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
