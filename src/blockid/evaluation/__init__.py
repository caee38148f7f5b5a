"""Validation of identified models: error metrics, simulation and prediction on data;
and the plant's best linear approximation measured from data."""

from blockid.evaluation.bla import best_linear_approximation, robust_bla
from blockid.evaluation.bla_result import BestLinearApproximation
from blockid.evaluation.frf import welch_bla
from blockid.evaluation.horizon import predict
from blockid.evaluation.metrics import (
    METRICS,
    fit_percent,
    max_absolute_error,
    mean_absolute_error,
    metrics_by_output,
    mse,
    rmse,
)
from blockid.evaluation.periods import find_period
from blockid.evaluation.residuals import ResidualAnalysis, residual_analysis
from blockid.evaluation.validate import MODES, ModelOutput, evaluate

__all__ = [
    "BestLinearApproximation",
    "best_linear_approximation",
    "find_period",
    "robust_bla",
    "welch_bla",
    "MODES",
    "ModelOutput",
    "evaluate",
    "predict",
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
