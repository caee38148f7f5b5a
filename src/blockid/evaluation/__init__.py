"""Validation of identified models: error metrics, simulation and prediction on data."""

from blockid.evaluation.metrics import (
    METRICS,
    fit_percent,
    max_absolute_error,
    mean_absolute_error,
    metrics_by_output,
    mse,
    rmse,
)
from blockid.evaluation.validate import MODES, ModelOutput, evaluate

__all__ = [
    "MODES",
    "ModelOutput",
    "evaluate",
    "METRICS",
    "fit_percent",
    "max_absolute_error",
    "mean_absolute_error",
    "metrics_by_output",
    "mse",
    "rmse",
]
