"""Validation of identified models: error metrics, simulation and prediction on data."""

from blockid.evaluation.horizon import k_step_prediction
from blockid.evaluation.metrics import (
    METRICS,
    fit_percent,
    max_absolute_error,
    mean_absolute_error,
    metrics_by_output,
    mse,
    rmse,
)
from blockid.evaluation.residuals import ResidualAnalysis, residual_analysis
from blockid.evaluation.validate import MODES, ModelOutput, evaluate

__all__ = [
    "MODES",
    "ModelOutput",
    "evaluate",
    "k_step_prediction",
    "ResidualAnalysis",
    "residual_analysis",
    "METRICS",
    "fit_percent",
    "max_absolute_error",
    "mean_absolute_error",
    "metrics_by_output",
    "mse",
    "rmse",
]
