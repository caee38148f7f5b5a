"""Confidence bands from parameter standard errors, by sampling the parameters.

On the plotting floor so that a fit's ``.plot()`` draws the bands the report draws.

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
    "BAND_DRAWS",
    "BAND_PERCENTILES",
    "fit_draws",
    "free_covariance",
    "free_standard_errors",
    "output_bands",
    "sampled_band",
    "sampled_models",
]

#: The percentiles of a 95 % band.
BAND_PERCENTILES = (2.5, 97.5)
#: Parameter vectors drawn for the bands on block curves.
BAND_DRAWS = 200


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
    # a parameter the data did not determine (an infinite standard error, null in JSON)
    return [np.nan if value is None else float(value)]


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


def fit_draws(fit: Any, n: int = BAND_DRAWS) -> list[Any]:
    """Models drawn from the uncertainty ``fit`` carries (:func:`sampled_models` with
    its covariance, or its standard errors), or an empty list when it carries none."""
    if fit is None or not hasattr(getattr(fit, "model", None), "free_parameters"):
        return []
    cov = free_covariance(fit)
    se = None if cov is not None else free_standard_errors(fit)
    if cov is None and se is None:
        return []
    return sampled_models(fit.model, se, n=n, covariance=cov)


def output_bands(fit: Any, output: Any, draws: Sequence[Any] = ()) -> tuple[list[Any], str]:
    """95 % bands of a free-run simulation (a :class:`~blockid.evaluation.ModelOutput`
    of ``fit.model``) per experiment, and a sentence that says what they are.

    With the covariance the fit carries: the band of the noise-free output, linearised
    along the simulation (:func:`blockid.evaluation.uncertainty.simulation_band`, as
    ``blockid simulate --band``); otherwise the band of the simulated output over up to
    100 of the drawn models; otherwise none.
    """
    record = (getattr(fit, "settings", None) or {}).get("covariance")
    if record is not None:
        from blockid.errors import BlockidError
        from blockid.evaluation.uncertainty import ParameterCovariance, simulation_band

        try:
            cov = ParameterCovariance.from_dict(record)
            bands = [
                simulation_band(fit.model, cov, x.u, x.y[: output.skip])
                for x in output.data.experiments
            ]
            return [(b.lower, b.upper) for b in bands], (
                " Shaded: 95 % confidence band of the noise-free output, from the parameter "
                "covariance linearised along the simulation (as 'blockid simulate --band')."
            )
        except (BlockidError, ValueError, KeyError, TypeError, np.linalg.LinAlgError):
            pass
    if draws:
        bands = [
            sampled_band(draws[:100], lambda m, x=x: m.simulate(x.u, x.y[: output.skip]))
            for x in output.data.experiments
        ]
        if any(b is not None for b in bands):
            return bands, (
                f" Shaded: 95 % band of the simulated output over {min(len(draws), 100)} "
                "parameter draws from the standard errors."
            )
    return [], " No uncertainty available for this model (no parameter standard errors)."
