"""Error metrics (SPEC "Definitions").

All functions take measured ``y`` and model output ``y_hat`` of equal shape, (N,) or
(N, ny), and return one value per output column. :func:`metrics_by_output` collects
them as JSON-ready objects keyed by metric, then output name, e.g.
``{"rmse": {"y1": 0.031, "y2": 0.0004}}``.

A metric that is undefined on the data (the fit percent of an output that is constant
over the scored samples) is NaN in these objects: a number, so tables print it and
comparisons skip it. JSON has no NaN, so every JSON writer passes its document through
:func:`json_safe`, which writes it as ``null``; :func:`undefined_notes` words the note
that goes with it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from blockid.data.io import json_safe
from blockid.errors import DataError

__all__ = [
    "mse",
    "rmse",
    "mean_absolute_error",
    "max_absolute_error",
    "fit_percent",
    "METRICS",
    "metrics_by_output",
    "json_safe",
    "undefined_notes",
]


def _pair(y: Any, y_hat: Any) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(y, dtype=float)
    y_hat = np.asarray(y_hat, dtype=float)
    if y.shape != y_hat.shape:
        raise DataError(f"measured output has shape {y.shape} but model output {y_hat.shape}")
    if y.ndim == 1:
        y, y_hat = y[:, None], y_hat[:, None]
    if y.shape[0] == 0:
        raise DataError("no samples to evaluate: the validation range is empty")
    return y, y_hat


def mse(y: Any, y_hat: Any) -> np.ndarray:
    """Mean squared error ``mean((y - y_hat)^2)``.

    >>> mse([1.0, 2.0], [1.0, 4.0]).tolist()
    [2.0]
    """
    y, y_hat = _pair(y, y_hat)
    return np.mean((y - y_hat) ** 2, axis=0)


def rmse(y: Any, y_hat: Any) -> np.ndarray:
    """Root mean squared error."""
    return np.sqrt(mse(y, y_hat))


def mean_absolute_error(y: Any, y_hat: Any) -> np.ndarray:
    """Mean absolute error ``mean(|y - y_hat|)``."""
    y, y_hat = _pair(y, y_hat)
    return np.mean(np.abs(y - y_hat), axis=0)


def max_absolute_error(y: Any, y_hat: Any) -> np.ndarray:
    """Maximum absolute error ``max |y - y_hat|`` (what paper A calls "MAE")."""
    y, y_hat = _pair(y, y_hat)
    return np.max(np.abs(y - y_hat), axis=0)


def fit_percent(y: Any, y_hat: Any) -> np.ndarray:
    """NRMSE fit ``100 (1 - |y - y_hat| / |y - mean(y)|)``; 100 is perfect, can be negative.

    For an output that is constant over the samples, ``|y - mean(y)|`` is zero and the
    fit is undefined: NaN (``null`` in JSON, see :func:`undefined_notes`), unless the
    model reproduces it exactly (100). It used to be ``-inf``, which no JSON writer
    accepts and which says nothing more than "undefined".

    >>> fit_percent([0.0, 2.0], [0.0, 2.0]).tolist()
    [100.0]
    >>> fit_percent([1.0, 1.0], [1.0, 1.5]).tolist()
    [nan]
    """
    y, y_hat = _pair(y, y_hat)
    den = np.linalg.norm(y - y.mean(axis=0), axis=0)
    num = np.linalg.norm(y - y_hat, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 100.0 * (1.0 - num / den)
    return np.where(den > 0, out, np.where(num > 0, np.nan, 100.0))


#: Metric name (as in JSON output) -> function.
METRICS = {
    "mse": mse,
    "rmse": rmse,
    "mae": mean_absolute_error,
    "max_abs_error": max_absolute_error,
    "fit_percent": fit_percent,
}


def metrics_by_output(
    y: Any, y_hat: Any, outputs: Sequence[str], skip: int = 0
) -> dict[str, dict[str, float]]:
    """Every metric of :data:`METRICS`, keyed by metric then output name.

    ``skip`` leaves out the first samples (a model's initial conditions).
    """
    y, y_hat = _pair(y, y_hat)
    y, y_hat = y[skip:], y_hat[skip:]
    if y.shape[0] == 0:
        raise DataError(f"no samples left to evaluate after the first {skip} (initial conditions)")
    if not np.all(np.isfinite(y_hat)):
        raise DataError("the model output is not finite: the model diverged on these data")
    return {
        name: dict(zip(outputs, (float(v) for v in fn(y, y_hat)), strict=True))
        for name, fn in METRICS.items()
    }


def undefined_notes(metrics: Mapping[str, Mapping[str, float]]) -> list[str]:
    """One note per metric and output that is undefined (NaN) in ``metrics``.

    >>> for note in undefined_notes({"fit_percent": {"y": float("nan")}, "mse": {"y": 0.1}}):
    ...     print(note.split(":")[0])
    fit_percent of output 'y' is undefined (null)
    """
    notes = []
    for name, values in metrics.items():
        for output, value in values.items():
            if value is None or (isinstance(value, float) and math.isnan(value)):
                why = (
                    "the output is constant over the scored samples"
                    if name == "fit_percent"
                    else "not defined on these samples"
                )
                notes.append(f"{name} of output {output!r} is undefined (null): {why}")
    return notes
