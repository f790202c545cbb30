"""The exception family of the ur_sim_driver package."""


class UrSimError(Exception):
    """Base class of every error raised by ur_sim_driver.

    Messages name the offending field, its value and the allowed range or choices,
    so that the ROS boundary can pass them on unchanged as a log line or an
    ``error_string``.
    """


class ConfigError(UrSimError):
    """A parameter, YAML key or model option is invalid."""


class TrajectoryError(UrSimError):
    """A trajectory is malformed or cannot be executed."""
