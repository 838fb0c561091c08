"""Exceptions raised by the twin: each names what was wrong and what is allowed."""

from os import PathLike


class TwinError(Exception):
    """Base class of every error the twin raises on bad input or failed computation."""


class UnknownPlatformError(TwinError, KeyError):
    """A platform or configuration name that the twin does not know."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class ModelFileError(TwinError):
    """A model folder or file is missing or malformed."""


class PoseError(TwinError, ValueError):
    """A pose array that is malformed: wrong shape or not finite."""


class OutOfStrokeError(TwinError, ValueError):
    """A pose or set of leg lengths that needs an actuator beyond its stroke."""


class ForwardKinematicsError(TwinError, ArithmeticError):
    """Newton-Raphson forward kinematics did not converge within its iteration budget."""


class SignalError(TwinError, ValueError):
    """A time signal that is malformed: wrong shape, rate, or not finite."""


class ActuatorLimitError(TwinError, ValueError):
    """Commands that need an actuator beyond its stroke, velocity or acceleration (strict mode)."""


class PhysicsDivergedError(TwinError, ArithmeticError):
    """A physics simulation that diverged (a non-finite state, or MuJoCo's own warnings)."""


class DataError(SignalError):
    """Recorded data (a run folder, a CSV, a pilot record) that cannot be used as given."""


class RunFormatError(DataError):
    """A recorded file or folder that does not follow its format (``twin-run/1``, ...)."""


class SignalLimitError(SignalError):
    """A command signal would break a platform's stroke, velocity or acceleration limit."""


class UsageError(TwinError, ValueError):
    """A command-line value that is not allowed (a range, a combination, an output path)."""


class ConfigError(SignalError):
    """A motion-system configuration (name, file or override) that is malformed."""


class OutputError(UsageError):
    """An output file or folder that cannot be written (disk full, permission denied, ...).

    Parameters
    ----------
    path : str or os.PathLike
        The output as the user named it (not the hidden name it is written under).
    reason : str
        Why it cannot be written, as the operating system says.

    """

    def __init__(self, path: str | PathLike[str], reason: str) -> None:
        super().__init__(f"{path}: cannot be written ({reason})")
        self.path = path
        self.reason = reason

    def __reduce__(self) -> tuple[type, tuple[str | PathLike[str], str]]:
        """Pickle by path and reason (a task's error crosses processes)."""
        return type(self), (self.path, self.reason)


class ScheduleError(DataError):
    """A test-schedule file (a ``MovementSeries`` or ``twin-schedule/1``) that cannot be run."""
