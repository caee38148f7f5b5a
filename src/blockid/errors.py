"""Exceptions raised by blockid.

Every error the user can cause derives from :class:`BlockidError`. Its message names
the problem and the fix (file, column, row, parameter); the command-line interface
prints it as a single line and exits non-zero, without a traceback.
"""

from __future__ import annotations

__all__ = [
    "BlockidError",
    "DataError",
    "OrderError",
    "ModelFileError",
    "EstimationError",
    "ParameterError",
    "SimulationError",
]


class BlockidError(ValueError):
    """Base class of every error blockid raises for bad input or a failed estimate.

    ``parameter`` names the Python parameter at fault when there is one (e.g.
    ``"forgetting"``), so that the command line can name its own flag for it.
    """

    def __init__(self, message: str = "", *, parameter: str | None = None) -> None:
        super().__init__(message)
        self.parameter = parameter


class DataError(BlockidError):
    """An input/output record is missing, malformed or does not fit the request."""


class OrderError(BlockidError):
    """Model orders or delays are invalid or too large for the data."""


class ParameterError(BlockidError):
    """An estimator or model option has an invalid value."""


class ModelFileError(BlockidError):
    """A model file is damaged, of an unknown format or of an unsupported version."""


class EstimationError(BlockidError):
    """An estimator failed: it diverged, produced non-finite values or an unstable model.

    Raised instead of returning a model that should not be trusted. A recursive fit asked
    to ``record_history`` attaches what it recorded up to the failure as ``history``
    (same keys as ``FitResult.history``: ``"theta"`` rows, ``"names"``, ``"update"``), so
    that the failure can be looked at; otherwise ``history`` is None.
    """

    history: dict | None = None


class SimulationError(BlockidError):
    """A model's output diverged on the data it was run on (not finite, or astronomically
    beyond the measured output's range): its metrics would mean nothing."""
