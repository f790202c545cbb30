"""The exception family of the ur_glue_planner package."""


class GluePlannerError(Exception):
    """Base class of every error raised by ur_glue_planner.

    Messages name the offending field or waypoint, the value and the limit.
    """


class JobError(GluePlannerError):
    """A glue job file is invalid."""


class PlanningError(GluePlannerError):
    """Path, IK or timing could not be computed within the limits."""


class ClientError(GluePlannerError):
    """A ROS interaction of the client API failed (server missing, goal rejected, timeout)."""
