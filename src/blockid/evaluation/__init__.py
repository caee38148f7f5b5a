"""Validation of identified models: error metrics."""

from blockid.evaluation.metrics import (
    METRICS,
    fit_percent,
    max_absolute_error,
    mean_absolute_error,
    metrics_by_output,
    mse,
    rmse,
)

__all__ = [
    "METRICS",
    "fit_percent",
    "max_absolute_error",
    "mean_absolute_error",
    "metrics_by_output",
    "mse",
    "rmse",
]
