"""One exception hierarchy for sonotrack.

Every error subclasses :class:`SonotrackError` and a builtin, so callers can catch either.
Messages name the file, component, port or field, the bad value and the valid choices.
"""

__all__ = [
    "SonotrackError",
    "ParameterError",
    "InputError",
    "ConfigError",
    "BuildError",
    "SimulationError",
    "RunInterrupted",
    "StepRejectedError",
]


class SonotrackError(Exception):
    """Base class of every sonotrack error."""


class ParameterError(SonotrackError, ValueError):
    """A model parameter is out of its valid range or of the wrong kind."""


class InputError(SonotrackError, ValueError):
    """A port input is not finite or outside its physical range."""


class ConfigError(SonotrackError, ValueError):
    """A scenario, system description or command-line value is invalid."""


class BuildError(SonotrackError, RuntimeError):
    """An FMU could not be built or post-processed."""


class SimulationError(SonotrackError, RuntimeError):
    """A co-simulation stopped because an FMU reported an error or discard."""


class RunInterrupted(SonotrackError, RuntimeError):
    """A run was stopped by a signal (SIGINT, SIGTERM) at a step boundary.

    Attributes
    ----------
    exit_status : int
        What the command line exits with: 128 + the signal number, as a shell reports it.
    """

    def __init__(self, message, signal_number=2):
        super().__init__(message)
        self.exit_status = 128 + int(signal_number)


class StepRejectedError(SonotrackError, RuntimeError):
    """A slave refuses one communication step; the host may retry it (FMI ``fmi2Discard``).

    Raised from ``do_step`` when the step cannot be taken as asked but the instance is intact
    (for example a step size the model cannot integrate). sonotrack's FMU binary maps it to
    ``fmi2Discard`` and logs the message; every other :class:`SonotrackError` gives
    ``fmi2Error`` (docs/fmi_binary.md).
    """
