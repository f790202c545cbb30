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


class ScriptError(UrSimError):
    """A URScript program cannot be compiled, or stopped with a runtime error.

    Attributes:
        line: the program's line it points at (1-based; 0 when it points at none).
        column: the column on that line (1-based; 0 when none).
    """

    def __init__(self, message: str, line: int = 0, column: int = 0) -> None:
        super().__init__(message)
        self.line = line
        self.column = column
