"""Fit ARX models with any of the regressor-level estimators.

Each output of a multi-output ARX model has its own regressor (its own orders), so
outputs are fitted one after another. Rows never straddle two experiments: each
experiment contributes the samples after its first ``max_lag`` ones. The recursive
estimators see the experiments one after another, in order.

Before a recursive estimator runs, every regressor column is divided by its RMS over
the estimation data. This changes nothing in exact arithmetic except the effective
``P(0)`` (which becomes scale-aware), so that "large initial covariance" means large
relative to the data: RLS with forgetting 1 then reproduces batch least squares to
about 1e-8 whatever the units of the signals. Online learning
(:mod:`blockid.fitting.online`) cannot know that RMS in advance: it divides each column
by a given scale of the signal it is a lag of, or by nothing, which ``scaling`` selects
here too (:func:`regressor_scale`).

Regressors are built ``regressor_rows`` rows at a time (:mod:`blockid.config`;
:func:`regressor_chunks`), so
a long record costs one chunk of regressors on top of the data, whatever its length:
batch least squares folds the chunks into one triangular factor, the recursive
estimators run chunk after chunk with their state carried over.

The fitted model is checked before it is returned: finite parameters, a stable
``A(z)`` (unless ``allow_unstable``), and, for the recursive methods, convergence: the
one-step mean squared error on the estimation data may not exceed ``max_mse_ratio``
times that of the exact least-squares solution (the smallest any parameter value can
reach). A recursion that has not converged (H-RLS without forgetting on correlated
regressors stalls this way, see docs/convergence.md) is reported, not returned.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.defaults import FORGETTING, RECURSIVE
from blockid.errors import EstimationError, OrderError, ParameterError
from blockid.estimators import (
    AdaptiveWeightedRLS,
    BatchLeastSquares,
    HierarchicalRLS,
    RecursiveLeastSquares,
)
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.options import checked
from blockid.fitting.result import FitResult
from blockid.models.arx import ARX

__all__ = [
    "ARX_METHODS",
    "fit_arx",
    "least_squares",
    "make_estimator",
    "regressor_chunks",
    "regressor_scale",
    "signal_scales",
]

#: Method names accepted by :func:`fit_arx` (and ``blockid fit --method``).
ARX_METHODS = ("batch", "rls", "aw-rls", "hierarchical-rls")


def make_estimator(
    method: str,
    *,
    forgetting: float | str | ForgettingSchedule = FORGETTING,
    initial_covariance: float | None = None,
    eps1: float = RECURSIVE["aw-rls"]["eps1"],  # type: ignore[assignment]
    eps2: float = RECURSIVE["aw-rls"]["eps2"],  # type: ignore[assignment]
    groups: Any = 2,
) -> Any:
    """Build the regressor-level estimator a method name stands for."""
    if method == "batch":
        return BatchLeastSquares()
    if method == "rls":
        return RecursiveLeastSquares(
            forgetting=forgetting,
            initial_covariance=initial_covariance or RECURSIVE["rls"]["initial_covariance"],
        )
    if method == "aw-rls":
        return AdaptiveWeightedRLS(
            eps1=eps1,
            eps2=eps2,
            initial_covariance=initial_covariance or RECURSIVE["aw-rls"]["initial_covariance"],
        )
    if method == "hierarchical-rls":
        return HierarchicalRLS(
            groups=groups,
            forgetting=forgetting,
            initial_covariance=initial_covariance
            or RECURSIVE["hierarchical-rls"]["initial_covariance"],
        )
    raise ParameterError(
        f"unknown method {method!r} for ARX; choose one of {', '.join(ARX_METHODS)}"
    )


def signal_scales(scaling: Any, n_inputs: int, n_outputs: int) -> Any:
    """Check ``scaling`` of :func:`fit_arx`: ``"rms"``, ``"none"``, or a pair
    ``(input_scales, output_scales)`` (a number or one per signal), returned as two
    arrays of positive finite numbers."""
    if isinstance(scaling, str) and scaling in ("rms", "none"):
        return scaling
    try:
        su, sy = scaling
        su = np.broadcast_to(np.asarray(su, dtype=float), (n_inputs,)).copy()
        sy = np.broadcast_to(np.asarray(sy, dtype=float), (n_outputs,)).copy()
    except (TypeError, ValueError):
        su = sy = np.array([np.nan])
    both = np.concatenate((su, sy))
    if not (np.all(np.isfinite(both)) and np.all(both > 0)):
        raise ParameterError(
            f"scaling must be 'rms', 'none' or a pair (input scales, output scales) of "
            f"positive numbers ({n_inputs} input(s), {n_outputs} output(s)), got {scaling!r}"
        )
    return su, sy


def regressor_chunks(
    model: ARX, data: Dataset, i: int, rows: int | None = None
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """``(Phi, target)`` of output ``i`` over ``data``, at most ``rows`` rows at a time
    (default: the ``regressor_rows`` of :func:`blockid.config.get_config`).

    Experiment after experiment, in order: stacked, the chunks are
    ``model.regressors`` of every experiment, but only one chunk is held at a time.
    """
    lag, rows = model.max_lag, rows or get_config()["regressor_rows"]
    for e in data.experiments:
        for start in range(lag, e.n_samples, rows):
            stop = min(start + rows, e.n_samples)
            yield model.regressors(e.u[start - lag : stop], e.y[start - lag : stop], i)


def least_squares(model: ARX, data: Dataset, i: int) -> np.ndarray:
    """Least-squares parameters of output ``i`` of ``model`` over ``data``, by chunks."""
    return BatchLeastSquares().fit_chunks(regressor_chunks(model, data, i)).coef_


def regressor_scale(model: ARX, i: int, scaling: Any, data: Dataset | None = None) -> np.ndarray:
    """Divisors of the regressor columns of output ``i`` before a recursive estimator runs.

    ``"rms"``: every column's RMS over ``data`` (1 for an all-zero column); ``"none"``:
    1; ``(input_scales, output_scales)`` from :func:`signal_scales`: the scale of the
    signal a column is a lag of (columns as :meth:`~blockid.models.ARX.regressors`).
    """
    if isinstance(scaling, str):
        if scaling == "none":
            return np.ones(model.n_parameters(i))
        squares, rows = np.zeros(model.n_parameters(i)), 0
        for Phi, _ in regressor_chunks(model, data, i):
            squares += np.sum(Phi**2, axis=0)
            rows += Phi.shape[0]
        scale = np.sqrt(squares / max(rows, 1))
        scale[scale == 0] = 1.0
        return scale
    su, sy = scaling
    parts = [np.full(model.na[i, j], sy[j]) for j in range(len(model.outputs))]
    parts += [np.full(model.nb[i, m], su[m]) for m in range(len(model.inputs))]
    return np.concatenate(parts) if parts else np.zeros(0)


def _advice(method: str, schedule: ForgettingSchedule, passes: int) -> str:
    """What to try after a recursion that did not converge, given what was used."""
    more = f"more passes (passes={passes} was used)"
    if method == "hierarchical-rls":
        if schedule.is_constant_one:
            return (
                f"H-RLS needs a forgetting factor below 1 (e.g. 0.98) and possibly {more}, "
                "see docs/convergence.md; or use method batch or rls"
            )
        return (
            f"forgetting {schedule} was used: try {more}, a factor closer to 1 (e.g. 0.995) "
            "so that the estimate settles, see docs/convergence.md; or use method batch or rls"
        )
    if schedule.is_constant_one:
        return f"use more data or {more}, or method batch"
    return (
        f"use more data or {more}, forgetting 1 (forgetting {schedule} was used), or method batch"
    )


#: Relative to the variance of the output, a one-step MSE below this floor counts as
#: converged whatever the least-squares optimum is: on noise-free data the optimum is
#: rounding noise (1e-31) that no recursion with forgetting reaches, and a recursive
#: estimate that predicts to 1e-8 of the output's variance is as good as it.
CONVERGENCE_FLOOR = 1e-8


def _check_converged(
    model: ARX,
    data: Dataset,
    i: int,
    theta: np.ndarray,
    method: str,
    ratio: float,
    advice: str,
) -> None:
    """Raise when a recursive estimate of output ``i`` is far from the least-squares
    optimum.

    The estimate passes when its one-step MSE is at most ``ratio`` times the optimum
    plus :data:`CONVERGENCE_FLOOR` times the variance of the output.
    """
    name = model.outputs[i]
    best = least_squares(model, data, i)
    sse_best = sse = total = total2 = 0.0
    rows = 0
    for Phi, target in regressor_chunks(model, data, i):
        sse_best += float(np.sum((target - Phi @ best) ** 2))
        sse += float(np.sum((target - Phi @ theta) ** 2))
        total += float(np.sum(target))
        total2 += float(np.sum(target**2))
        rows += target.shape[0]
    mse_best, mse = sse_best / rows, sse / rows
    variance = max(total2 / rows - (total / rows) ** 2, 0.0)
    floor = CONVERGENCE_FLOOR * variance + 1e-300
    if mse > ratio * mse_best + floor:
        raise EstimationError(
            f"output {name!r}: {method} did not converge: its one-step MSE on the estimation "
            f"data, {mse:.4g}, is {mse / max(mse_best, floor):.3g} times the least-squares "
            f"optimum {mse_best:.4g} (and above {CONVERGENCE_FLOOR:g} of the output's "
            f"variance). {advice}; for a plant that really varies in time, switch this check "
            "off (convergence_check=False)"
        )


def _check_inputs_used(model: ARX) -> None:
    """Refuse an output that no input drives (``nb`` 0 for every input)."""
    for i, name in enumerate(model.outputs):
        if not model.nb[i].any():
            inputs = ", ".join(repr(u) for u in model.inputs)
            raise OrderError(
                f"nb is 0 for every input of output {name!r} ({inputs}): the model would "
                "not use any input (a pure autoregression that free-run simulation cannot "
                "drive); give nb >= 1, the number of coefficients of an input"
                + (", for at least one input" if len(model.inputs) > 1 else ""),
                parameter="nb",
            )


def _rank_deficient(exc: EstimationError, model: ARX, i: int, data: Dataset) -> EstimationError:
    """The least-squares rank error of output ``i`` with its regressors named by signal
    and lag, and the signals that are constant over the data."""
    columns = getattr(exc, "columns", None) or []
    yi = model.outputs[i]
    lags = [(yj, k) for j, yj in enumerate(model.outputs) for k in range(1, model.na[i, j] + 1)]
    lags += [
        (um, int(model.nk[i, m]) + k)
        for m, um in enumerate(model.inputs)
        for k in range(model.nb[i, m])
    ]  # the columns of ARX.regressors, in order
    shown = ", ".join(f"{lags[k][0]} at lag {lags[k][1]}" for k in columns if k < len(lags))
    shown = shown or "some regressors"
    constant = [
        f"{kind} {signal!r} is constant over the estimation data ({values[0]:.6g} at every sample)"
        for kind, signal, values in _regressed(model, i, data)
        if np.ptp(values) == 0.0
    ]
    glitches = _glitches(model, i, data)
    why = (
        "; ".join(constant) + ": a constant signal tells nothing about the dynamics and its "
        "lags repeat one another; use data in which it varies"
        if constant
        else "; ".join(glitches) + ": one sample that size swamps every other in the "
        "normal equations; remove or correct that row"
        if glitches
        else "the data do not excite the model enough, or the orders are too high"
    )
    return EstimationError(
        f"output {yi!r}: least squares is rank deficient: the regressors {shown} are "
        f"(nearly) linear combinations of the others; {why}"
    )


#: A sample this many median absolute deviations from its signal's median is a glitch.
GLITCH = 1e6


def _glitches(model: ARX, i: int, data: Dataset) -> list[str]:
    """The regressed signals of output ``i`` with a sample :data:`GLITCH` or more median
    absolute deviations from their median (a 1e12 among values near 1), each named with
    its row in the estimation data."""
    found = []
    for kind, signal, values in _regressed(model, i, data):
        with np.errstate(all="ignore"):
            deviation = np.abs(values - np.median(values))
            typical = float(np.median(deviation))
        if typical > 0 and np.all(np.isfinite(deviation)):
            k = int(np.argmax(deviation))
            if deviation[k] >= GLITCH * typical:
                found.append(
                    f"{kind} {signal!r} is {values[k]:.6g} at row {k} (0-based) of the "
                    f"estimation data, {deviation[k] / typical:.2g} times its median deviation"
                )
    return found


def _regressed(model: ARX, i: int, data: Dataset) -> Iterator[tuple[str, str, np.ndarray]]:
    """``(kind, name, values over the data)`` of each signal in output ``i``'s
    regressors (an order above zero)."""
    for kind, signals, orders in (
        ("input", model.inputs, model.nb[i]),
        ("output", model.outputs, model.na[i]),
    ):
        for j, signal in enumerate(signals):
            if orders[j] > 0:
                yield kind, signal, np.concatenate(data.signal(signal))


def fit_arx(
    data: Dataset,
    na: Any = 1,
    nb: Any = 1,
    nk: Any = 1,
    *,
    method: str = "batch",
    forgetting: float | str | ForgettingSchedule = FORGETTING,
    initial_covariance: float | None = None,
    eps1: float = RECURSIVE["aw-rls"]["eps1"],  # type: ignore[assignment]
    eps2: float = RECURSIVE["aw-rls"]["eps2"],  # type: ignore[assignment]
    center: bool = False,
    allow_unstable: bool = False,
    passes: int = 1,
    max_mse_ratio: float | None = 2.0,
    scaling: Any = "rms",
) -> FitResult:
    """Identify an ARX model from a :class:`~blockid.data.Dataset`.

    Parameters
    ----------
    data : Dataset
        Estimation data (already restricted to the estimation range).
    na, nb, nk : int or matrix
        Orders in the MATLAB convention (see :class:`~blockid.models.ARX`).
    method : {"batch", "rls", "aw-rls", "hierarchical-rls"}
    forgetting : float, str or ForgettingSchedule
        Forgetting factor or schedule (``"0.98:200,1"``) of the RLS methods, read once
        here (a bad value fails before any data work) and handed to the estimators as a
        :class:`~blockid.estimators.forgetting.ForgettingSchedule`.
    initial_covariance : float, optional
        ``P(0)`` relative to the RMS-scaled regressors (defaults 1e8; 1e5 for AW-RLS).
    eps1, eps2 : float
        AW-RLS weights (A8).
    center : bool
        Fit around the operating point: subtract the mean of every signal over the
        estimation data and keep it in the model as offsets.
    allow_unstable : bool
        Return a model whose ``A(z)`` has poles on or outside the unit circle instead
        of raising :class:`~blockid.errors.EstimationError`.
    passes : int
        Passes of a recursive method over the data (state carried over; forgetting
        schedules count samples across passes).
    max_mse_ratio : float or None
        Convergence check of the recursive methods (None to skip, e.g. for a plant that
        really varies in time): raise when the one-step MSE on the estimation data is
        more than this multiple of the least-squares optimum.
    scaling : "rms", "none" or (input_scales, output_scales)
        What a recursive method divides the regressor columns by (and what
        ``initial_covariance`` is relative to): their RMS over the estimation data
        (default), nothing, or the given scale of the signal each column is a lag of
        (a number or one per signal), as online learning does
        (:mod:`blockid.fitting.online`).
    """
    if method not in ARX_METHODS:
        raise ParameterError(
            f"unknown method {method!r} for ARX; choose one of {', '.join(ARX_METHODS)}"
        )
    passes = checked("passes", passes)  # the options' one declaration
    schedule = ForgettingSchedule.parse(forgetting)  # once, not per output and chunk
    u_off = y_off = None
    if center:
        u_off = np.mean(np.vstack([e.u for e in data.experiments]), axis=0)
        y_off = np.mean(np.vstack([e.y for e in data.experiments]), axis=0)
    scaling = signal_scales(scaling, len(data.inputs), len(data.outputs))
    model = ARX(
        data.inputs,
        data.outputs,
        na,
        nb,
        nk,
        sampling_time=data.sampling_time,
        input_offset=u_off,
        output_offset=y_off,
    )
    _check_inputs_used(model)
    n_par_max = max(model.n_parameters(i) for i in range(len(model.outputs)))
    data.check_orders(model.max_lag, n_par_max, what="ARX orders")
    settings: dict[str, Any] = {
        "na": model.na.tolist(),
        "nb": model.nb.tolist(),
        "nk": model.nk.tolist(),
        "center": center,
    }
    if method != "batch":
        settings["passes"] = int(passes)
    if method in ("rls", "hierarchical-rls"):
        settings["forgetting"] = str(forgetting)
    if method == "aw-rls":
        settings.update(eps1=eps1, eps2=eps2)
    if initial_covariance is not None:
        settings["initial_covariance"] = initial_covariance

    for i, name in enumerate(model.outputs):
        if model.n_parameters(i) == 0:
            continue
        est = make_estimator(
            method,
            forgetting=schedule,
            initial_covariance=initial_covariance,
            eps1=eps1,
            eps2=eps2,
            groups=model.hierarchical_groups(i),
        )
        if method == "batch":
            try:
                theta = est.fit_chunks(regressor_chunks(model, data, i)).coef_
            except EstimationError as exc:
                raise _rank_deficient(exc, model, i, data) from None
        else:
            scale = regressor_scale(model, i, scaling, data)
            try:
                for _ in range(int(passes)):  # chunk after chunk, experiment after experiment
                    for Phi, target in regressor_chunks(model, data, i):
                        est.partial_fit(Phi / scale, target)
            except EstimationError as exc:
                raise EstimationError(f"output {name!r}: {exc}") from None
            theta = est.coef_ / scale
            if max_mse_ratio is not None:
                try:
                    _check_converged(
                        model,
                        data,
                        i,
                        theta,
                        method,
                        max_mse_ratio,
                        _advice(method, schedule, int(passes)),
                    )
                except EstimationError as exc:
                    if getattr(exc, "columns", None) is None:
                        raise
                    raise _rank_deficient(exc, model, i, data) from None
        if not np.all(np.isfinite(theta)):
            raise EstimationError(f"output {name!r}: the {method} estimate is not finite")
        model.set_parameter_vector(i, theta)

    if not allow_unstable and not model.is_stable():
        rho = float(np.max(np.abs(model.poles())))
        raise EstimationError(
            f"the identified ARX model is unstable (largest pole magnitude {rho:.4g} >= 1): "
            "its free-run simulation would diverge. Check the orders and delays, use more or "
            "better-exciting data, or pass allow_unstable=True if you only need one-step prediction"
        )
    y_hat = [model.predict(e.u, e.y) for e in data.experiments]
    y_all = np.vstack([e.y[model.max_lag :] for e in data.experiments])
    yh_all = np.vstack([yh[model.max_lag :] for yh in y_hat])
    metrics = metrics_by_output(y_all, yh_all, model.outputs)
    return FitResult(
        model=model,
        method=method,
        settings=settings,
        estimation_metrics=metrics,
        n_samples=data.n_samples,
    )
