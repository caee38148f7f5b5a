"""Confidence bands from parameter standard errors, by sampling the parameters.

A fit may carry standard errors of its parameters (``FitResult.standard_errors``,
``FitResult.settings["standard_errors"]`` or ``model.standard_errors``). They are
matched to the model's free parameter vector (:meth:`ChainModel.free_parameters`),
parameter vectors are drawn from independent normals with those standard deviations
(clipped to the parameter bounds), and the 2.5 and 97.5 percentiles of whatever the
drawn models compute form a 95 % band. Independent draws ignore correlations between
parameters, so the band is indicative: it says how far the curve can move, not a
joint confidence region.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["BAND_PERCENTILES", "free_standard_errors", "sampled_band", "sampled_models"]

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


def sampled_models(model: Any, se: np.ndarray, n: int = 200, seed: int = 0) -> list[Any]:
    """Up to ``n`` copies of ``model`` with free parameters drawn from
    ``N(theta, diag(se**2))`` inside the parameter bounds (draws the model refuses are
    skipped)."""
    rng = np.random.default_rng(seed)
    theta = np.asarray(model.free_parameters(), float)
    low, high = model.parameter_bounds()
    out = []
    for _ in range(n):
        draw = np.clip(theta + se * rng.standard_normal(theta.size), low, high)
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
