"""Exceptions raised by jointwear, and the CLI exit code each one maps to.

Every error jointwear raises on purpose is a :class:`JointwearError`. Its message names the
file or parameter involved, what was expected, what was found and what to do. The CLI turns
them into a message on stderr (no traceback unless ``--debug``) and an exit code:

====  =====================================================================
code  meaning
====  =====================================================================
0     success
1     a validation criterion failed (:class:`ValidationFailed`)
2     usage error (bad command line; raised by the CLI parser)
3     bad input, or a computation that cannot go on (:class:`BadInputError`,
      :class:`SimulationError`, ...)
====  =====================================================================
"""

from __future__ import annotations

__all__ = [
    "JointwearError",
    "BadInputError",
    "ConventionError",
    "ParameterError",
    "SimulationError",
    "CalibrationError",
    "ValidationFailed",
    "EXIT_OK",
    "EXIT_VALIDATION_FAILED",
    "EXIT_USAGE",
    "EXIT_BAD_INPUT",
]

EXIT_OK = 0
EXIT_VALIDATION_FAILED = 1
EXIT_USAGE = 2
EXIT_BAD_INPUT = 3


class JointwearError(Exception):
    """Base class of all deliberate jointwear errors."""

    exit_code: int = EXIT_BAD_INPUT


class BadInputError(JointwearError, ValueError):
    """An input file, array or option is malformed, inconsistent or unsupported."""


class ConventionError(BadInputError):
    """A dataset does not follow the data contract (units, angle convention, attributes)."""


class ParameterError(BadInputError, KeyError):
    """A parameter is unknown, missing, of the wrong type or out of its physical range."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class SimulationError(JointwearError, RuntimeError):
    """A simulation cannot go on (diverging solve, step-size collapse, excessive penetration).

    Attributes
    ----------
    partial : object or None
        Whatever was computed before the failure (e.g. an :class:`xarray.Dataset`), so that it
        can be saved and inspected.
    """

    def __init__(self, message: str, *, partial: object | None = None) -> None:
        super().__init__(message)
        self.partial = partial


class CalibrationError(JointwearError, RuntimeError):
    """A camera calibration failed or is not trustworthy (too few views, high residuals)."""


class ValidationFailed(JointwearError):
    """A validation criterion failed (simulation and measurement disagree beyond tolerance)."""

    exit_code = EXIT_VALIDATION_FAILED
