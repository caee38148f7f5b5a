"""Confidence bands from parameter standard errors, by sampling the parameters.

A fit made with ``standard_errors=True`` carries the covariance of its free parameters
in ``settings["covariance"]`` (:func:`blockid.evaluation.uncertainty.with_standard_errors`)
and their standard errors in ``settings["standard_errors"]``. Parameter vectors are drawn
from the normal distribution with that covariance (or, with standard errors only, from
independent normals), clipped to the parameter bounds, and the 2.5 and 97.5 percentiles
of whatever the drawn models compute (a static block's curve) form a 95 % band. The
simulated output's band is the linearised one of
:func:`blockid.evaluation.uncertainty.simulation_band` (``blockid simulate --band``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = [
    "BAND_PERCENTILES",
    "free_covariance",
    "free_standard_errors",
    "sampled_band",
    "sampled_models",
]

#: The percentiles of a 95 % band.
BAND_PERCENTILES = (2.5, 97.5)


def _raw_standard_errors(fit: Any) -> Any:
    for source in (fit, getattr(fit, "model", None)):
        value = getattr(source, "standard_errors", None)
        if value is not None:
            return value
    settings = getattr(fit, "settings", None)
    return settings.get("standard_errors") if isinstance(settings, Mapping) else None


def _flatten(value: Any) -> list[float]:
    if isinstance(value, Mapping):
        return [x for v in value.values() for x in _flatten(v)]
    if isinstance(value, str | bytes):
        return []
    if isinstance(value, Sequence | np.ndarray):
        return [x for v in value for x in _flatten(v)]
    if isinstance(value, bool):
        return []
    return [float(value)]


def free_standard_errors(fit: Any) -> np.ndarray | None:
    """Standard errors of ``fit.model.free_parameters()``, or None when unavailable.

    Accepted forms: a vector as long as the free parameters; a mapping from the free
    parameter names (``a_1``, ``f_0``, ``q_2`` ..) to numbers; or a mapping of the same
    shape as ``model.parameters`` (``{"a": [..], "b": [..], "f": [..]}``), matched to
    the free parameters by value, in order.
    """
    raw = _raw_standard_errors(fit)
    model = getattr(fit, "model", None)
    if raw is None or not hasattr(model, "free_parameters"):
        return None
    theta = np.asarray(model.free_parameters(), float)
    names = list(model.free_parameter_names())
    if isinstance(raw, Mapping) and all(n in raw for n in names):
        se = [raw[n] for n in names]
    elif isinstance(raw, Mapping):
        values = _flatten(getattr(model, "parameters", {}))
        errors = _flatten({k: raw.get(k, []) for k in getattr(model, "parameters", {})})
        if len(values) != len(errors):
            return None
        se, pos = [], 0
        for value in theta:  # the free parameters appear in the same order, some left out
            while pos < len(values) and values[pos] != value:
                pos += 1
            if pos == len(values):
                return None
            se.append(errors[pos])
            pos += 1
    else:
        se = _flatten(raw)
    se_arr = np.asarray(se, float).reshape(-1)
    if se_arr.size != theta.size or not np.all(np.isfinite(se_arr)) or np.any(se_arr < 0):
        return None
    return se_arr


def free_covariance(fit: Any) -> np.ndarray | None:
    """The covariance of ``fit.model.free_parameters()`` stored by
    :func:`blockid.evaluation.uncertainty.with_standard_errors` in
    ``fit.settings["covariance"]``, or None (none stored, other parameter names, or a
    parameter the data did not determine)."""
    settings = getattr(fit, "settings", None)
    record = settings.get("covariance") if isinstance(settings, Mapping) else None
    model = getattr(fit, "model", None)
    if not isinstance(record, Mapping) or not hasattr(model, "free_parameters"):
        return None
    if list(record.get("names", ())) != list(model.free_parameter_names()):
        return None
    matrix = np.array(
        [[np.inf if v is None else float(v) for v in row] for row in record["matrix"]]
    )
    return matrix if np.all(np.isfinite(matrix)) else None


def sampled_models(
    model: Any,
    se: np.ndarray | None = None,
    n: int = 200,
    seed: int = 0,
    covariance: np.ndarray | None = None,
) -> list[Any]:
    """Up to ``n`` copies of ``model`` with free parameters drawn from
    ``N(theta, covariance)`` (or ``N(theta, diag(se**2))``) inside the parameter bounds
    (draws the model refuses are skipped)."""
    rng = np.random.default_rng(seed)
    theta = np.asarray(model.free_parameters(), float)
    low, high = model.parameter_bounds()
    if covariance is not None:
        steps = rng.multivariate_normal(np.zeros(theta.size), covariance, n, method="eigh")
    else:
        steps = np.asarray(se, float) * rng.standard_normal((n, theta.size))
    out = []
    for step in steps:
        draw = np.clip(theta + step, low, high)
        try:
            out.append(model.with_free_parameters(draw))
        except Exception:  # noqa: BLE001 - a draw the model refuses is left out
            continue
    return out


def sampled_band(
    models: Sequence[Any], compute: Callable[[Any], np.ndarray]
) -> tuple[np.ndarray, np.ndarray] | None:
    """The 95 % band (lower, upper) of ``compute(model)`` over the drawn models
    (draws whose result is not finite are left out; None if fewer than 10 remain)."""
    values = []
    with np.errstate(all="ignore"):
        for m in models:
            try:
                v = np.asarray(compute(m), float)
            except Exception:  # noqa: BLE001 - a draw that cannot run is left out
                continue
            if np.all(np.isfinite(v)):
                values.append(v)
    if len(values) < 10:
        return None
    lo, hi = np.percentile(np.stack(values), BAND_PERCENTILES, axis=0)
    return lo, hi
