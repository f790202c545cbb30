"""The client API for scripts (seed 2), at its public path: ``from ur_glue_planner.client import URClient``.

The implementation lives in :mod:`ur_glue_planner.execution.client` (recordings in ``joint_state_recording``, goals
in ``trajectory_goal``), beside the planner's other ROS code; this module only re-exports its public names so that
user scripts do not depend on the package's internal layout.
"""
from ur_glue_planner.execution.client import DEFAULT_CONTROLLER, URClient
from ur_glue_planner.execution.joint_state_recording import JointStateRecorder, JointStateSample, Recording
from ur_glue_planner.execution.trajectory_goal import GoalOutcome, TrajectoryGoal

__all__ = ['DEFAULT_CONTROLLER', 'GoalOutcome', 'JointStateRecorder', 'JointStateSample', 'Recording',
           'TrajectoryGoal', 'URClient']
