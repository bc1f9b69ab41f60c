"""Named errors raised by ssw. Library code raises these; the CLI turns them into messages."""


class SswError(Exception):
    """Base class of every error ssw raises on purpose."""


class ConfigError(SswError, ValueError):
    """A configuration or command-line value is not allowed.

    The message names the field, the value and what is allowed.

    Parameters
    ----------
    field : str
        The field (config path or flag).
    value : object
        The value given.
    allowed : str
        What is allowed, and the way on.
    """

    def __init__(self, field: str, value: object, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"{field} = {value!r} is not allowed: {allowed}")


class SolverError(SswError, RuntimeError):
    """A numerical solve failed or did not converge (the reason is in the message)."""


class MeshError(SswError, RuntimeError):
    """A mesh could not be built or is degenerate."""


class OutOfRangeError(SswError, ValueError):
    """A value lies outside the range a table or inverse covers (the message gives it)."""


class RecordingError(SswError, ValueError):
    """A recording is empty, truncated, clipped, in the wrong units or otherwise unusable."""


class DaqError(SswError, RuntimeError):
    """Acquisition hardware or its driver is missing or failed."""


class CalibrationError(SswError, RuntimeError):
    """A calibration that cannot be trusted (not converged, a misfit beyond its statistics,
    parameters the references do not identify, reference TOFs the device cannot produce):
    refused, never written."""
