"""The client API for scripts (seed 2), at its public path: ``from ur_glue_planner.client import URClient``.

The implementation lives in :mod:`ur_glue_planner.execution.client`, beside the planner's other ROS code; this module
only re-exports its public names so that user scripts do not depend on the package's internal layout.
"""
from ur_glue_planner.execution.client import (
    DEFAULT_CONTROLLER,
    GoalOutcome,
    JointStateRecorder,
    JointStateSample,
    Recording,
    TrajectoryGoal,
    URClient,
)

__all__ = ['DEFAULT_CONTROLLER', 'GoalOutcome', 'JointStateRecorder', 'JointStateSample', 'Recording',
           'TrajectoryGoal', 'URClient']
