"""Fitting a linear block with a static nonlinearity in feedback (:class:`LinearFeedback`).

The start is an equation-error fit. Expanding the model
(:mod:`blockid.models.feedback`) with ``d_im = b_i c_m`` makes it linear in its
parameters,

.. math::

    y(k) = -\\sum_{j=1}^{n_a} a_j y(k-j) + \\sum_{i=0}^{n_b-1} b_i u(k-n_k-i)
           - \\sum_{i=0}^{n_b-1} \\sum_{m=2}^{r} d_{im}\\, y(k-n_k-i)^m + e(k),

which least squares solves (QR on RMS-scaled columns). ``[b | D]`` is ``b [1, c^T]``,
rank one; its rank-one factor (SVD, normalised so that the first entry of the right
factor is 1) gives ``b`` and ``c`` together. A second candidate keeps the regression's
``b`` and projects ``D`` on it (``c = D^T b / |b|^2``), and a third is the plain linear
ARX with ``c = 0``. Poles outside the unit circle are reflected inside. The candidate
with the smallest free-run simulation error on the estimation data starts the
refinement on simulation error (:func:`blockid.fitting.simulation_error.refine`,
Gauss-Newton with the model's own Jacobian :meth:`LinearFeedback.simulate_with_sensitivities`),
which removes the equation-error bias and ends with
:func:`~blockid.fitting.checks.check_model` (finite, stable, not worse than a linear
ARX of the same orders).

Other fed-back blocks (``feedback_block=``: dead zone, saturation, piecewise-linear with
fixed or free breakpoints, a user's block) start the same way, shape by shape: the
block's :meth:`~blockid.blocks.base.Block.initial_grid` on the range of the measured
output gives shapes that are either families linear in some parameters (a dead zone
with fixed edges is linear in its slopes, a piecewise-linear map in its values) or fixed
shapes to be scaled (a unit-slope saturation). For a family ``N(y) = g(y)^T θ`` the
regression above has the columns ``-g_l(y(k-n_k-i))`` and ``[b | D] = b [1, θ^T]``
is again rank one; for a fixed shape ``s`` the columns ``-s(y(k-n_k-i))`` give
``d = b γ`` and the block ``γ s`` (``γ = d^T b / |b|^2``, kept only where the block
allows it, e.g. positive slopes). A block linear in its parameters is its own family.
Every shape is scored by its free-run error, and the best starts the refinement. A
block with neither a grid nor linear parameters starts as given.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from blockid.blocks import Polynomial
from blockid.blocks.base import LinearFamily, StaticBlock
from blockid.blocks.linear import LinearBlock
from blockid.data.dataset import Dataset
from blockid.defaults import MAX_NFEV, PATIENCE, TAIL_FRACTION, TOLERANCE
from blockid.errors import BlockidError, EstimationError, ParameterError
from blockid.fitting.checks import simulation_mse, stability_margin
from blockid.fitting.initial import _lagged, _least_squares, _stabilise
from blockid.fitting.options import checked
from blockid.fitting.result import FitResult
from blockid.fitting.simulation_error import refine
from blockid.models.feedback import LinearFeedback

__all__ = ["fit_feedback", "initial_feedback", "initial_feedback_block"]


def _regression(
    data: Dataset, na: int, nb: int, nk: int, r: int, n0: int
) -> tuple[np.ndarray, np.ndarray]:
    """Equation-error regressors ``[-y(k-j), u(k-nk-i), -y(k-nk-i)^m]`` and ``y(k)``."""

    def powers(y: np.ndarray) -> np.ndarray:
        return np.column_stack([y**m for m in range(2, r + 1)]) if r >= 2 else y[:, None][:, :0]

    return _shape_regression(data, na, nb, nk, n0, powers)


def _candidates(
    template: LinearFeedback, data: Dataset, r: int
) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Starting ``(a, b, c)`` by name (module docstring)."""
    na, nb, nk, n0 = template.na, template.nb, template.nk, template.max_lag
    Phi, target = _regression(data, na, nb, nk, r, n0)
    n_lin = na + nb
    out: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    theta = _least_squares(Phi[:, :n_lin], target, "linear ARX")
    margin = stability_margin(data)
    out["linear ARX (c = 0)"] = (_stabilise(theta[:na], margin), theta[na:], np.zeros(r - 1))
    if r < 2:
        return out
    try:
        theta = _least_squares(Phi, target, "equation error with feedback terms")
    except EstimationError:
        return out  # e.g. y too small for its powers to be told apart: start linear
    a, b = _stabilise(theta[:na], margin), theta[na:n_lin]
    D = theta[n_lin:].reshape(nb, r - 1)  # D[i, m - 2] = b_i c_m
    U, s, Vt = np.linalg.svd(np.column_stack((b, D)), full_matrices=False)
    if abs(Vt[0, 0]) > 1e-8:  # [b | D] = s u v^T = b [1, c]
        out["equation error, rank one"] = (a, U[:, 0] * s[0] * Vt[0, 0], Vt[0, 1:] / Vt[0, 0])
    if nb > 1 and b @ b > 0:
        out["equation error, b kept"] = (a, b, D.T @ b / (b @ b))
    return out


def initial_feedback(
    data: Dataset, *, na: int, nb: int, nk: int, r: int = 3
) -> tuple[LinearFeedback, dict[str, float]]:
    """The equation-error start (module docstring) and the free-run MSE of every
    candidate; the model is the candidate with the smallest one."""
    template = LinearFeedback.template(
        data.inputs, data.outputs, na=na, nb=nb, nk=nk, r=r, sampling_time=data.sampling_time
    )
    data.check_orders(
        template.max_lag, template.free_parameters().size, what=f"feedback model r={r}"
    )
    models: dict[str, LinearFeedback] = {}
    scores: dict[str, float] = {}
    for name, (a, b, c) in _candidates(template, data, r).items():
        models[name] = template.replace(
            linear=LinearBlock(na, nb, nk, a, b),
            feedback=Polynomial(np.concatenate(([0.0], c)), constant=False),
        )
        with np.errstate(all="ignore"):
            scores[name] = simulation_mse(models[name], data)
    finite = [name for name, mse in scores.items() if np.isfinite(mse)]
    if not finite:
        raise EstimationError(
            "the feedback model's initial estimate explodes in free-run simulation for every "
            "candidate; try other orders (na, nb, nk) or a lower degree r"
        )
    return models[min(finite, key=scores.__getitem__)], scores


def _shape_regression(
    data: Dataset, na: int, nb: int, nk: int, n0: int, basis: Any
) -> tuple[np.ndarray, np.ndarray]:
    """Regressors ``[-y(k-j), u(k-nk-i), -g_l(y(k-nk-i))]`` for a basis ``g(y)`` (N, p)
    (``p = 0``: the linear ARX), and the targets ``y(k)``."""
    rows, targets = [], []
    for e in data.experiments:
        u, y = e.u[:, 0], e.y[:, 0]
        g = np.asarray(basis(y), dtype=float)
        g = g[:, None] if g.ndim == 1 else g
        cols = [-_lagged(y, j, n0) for j in range(1, na + 1)]
        cols += [_lagged(u, nk + i, n0) for i in range(nb)]
        cols += [-_lagged(g[:, m], nk + i, n0) for i in range(nb) for m in range(g.shape[1])]
        rows.append(np.column_stack(cols))
        targets.append(y[n0:])
    return np.vstack(rows), np.concatenate(targets)


def _minimum_norm_fit(Phi: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Least squares on RMS-scaled columns, minimum norm: a block that holds a linear
    term (a piecewise-linear map) repeats the ``-y(k-n_k-i)`` columns of ``A``, the one
    direction the model leaves free (:mod:`blockid.models.feedback`)."""
    scale = np.sqrt(np.mean(Phi**2, axis=0))
    scale[~(scale > 0)] = 1.0
    return np.linalg.lstsq(Phi / scale, target, rcond=None)[0] / scale


def _shape_start(data: Dataset, template: LinearFeedback, shape: Any) -> LinearFeedback | None:
    """The equation-error start for one shape of the fed-back block (module docstring),
    or None where the regression or the block refuses it."""
    na, nb, nk, n0 = template.na, template.nb, template.nk, template.max_lag
    if isinstance(shape, LinearFamily):
        basis, build = shape.regressors, shape.build
    elif shape.linear_in_parameters:
        basis, build = shape.regressors, shape.with_vector
    else:
        basis, build = (lambda y: shape(y)), None
    try:
        Phi, target = _shape_regression(data, na, nb, nk, n0, basis)
        theta = _minimum_norm_fit(Phi, target)
        if not np.all(np.isfinite(theta)):
            return None
        a, b = _stabilise(theta[:na], stability_margin(data)), theta[na : na + nb]
        D = theta[na + nb :].reshape(nb, -1)  # D[i] = b_i theta_N
        if build is not None:
            U, sv, Vt = np.linalg.svd(np.column_stack((b, D)), full_matrices=False)
            if abs(Vt[0, 0]) <= 1e-8:
                return None
            b, block = U[:, 0] * sv[0] * Vt[0, 0], build(Vt[0, 1:] / Vt[0, 0])
        else:
            gain = float(D[:, 0] @ b / (b @ b)) if b @ b > 0 else 0.0
            if not gain > 0:
                return None
            block = shape.scaled(gain)
        return template.replace(linear=LinearBlock(na, nb, nk, a, b), feedback=block)
    except BlockidError:
        return None


def initial_feedback_block(
    data: Dataset, *, na: int, nb: int, nk: int, block: StaticBlock
) -> tuple[LinearFeedback, dict[str, float]]:
    """The start for a fed-back ``block`` other than a polynomial (module docstring) and
    the free-run MSE of every shape tried; the model is the best of them."""
    y_all = np.concatenate([e.y[:, 0] for e in data.experiments])
    adapt = getattr(block, "adapted", None)
    block = adapt(y_all) if adapt is not None else block
    template = LinearFeedback(
        data.inputs,
        data.outputs,
        linear=LinearBlock(na, nb, nk),
        feedback=block,
        sampling_time=data.sampling_time,
    )
    data.check_orders(
        template.max_lag, template.free_parameters().size, what=f"feedback model {block.kind}"
    )
    shapes: list[Any] = list(block.initial_grid(y_all))
    if not shapes and block.linear_in_parameters:
        shapes = [block]
    models: dict[str, LinearFeedback] = {}
    for k, shape in enumerate(shapes):
        model = _shape_start(data, template, shape)
        if model is not None:
            models[f"equation error, shape {k + 1} of {len(shapes)}"] = model
    if not models:  # no grid, or every shape refused: the block as given on the ARX
        Phi, target = _regression(data, na, nb, nk, 1, template.max_lag)
        theta = _least_squares(Phi, target, "linear ARX")
        models["linear ARX, block as given"] = template.replace(
            linear=LinearBlock(
                na, nb, nk, _stabilise(theta[:na], stability_margin(data)), theta[na:]
            )
        )
    scores = {}
    for name, model in models.items():
        with np.errstate(all="ignore"):
            scores[name] = simulation_mse(model, data)
    finite = [name for name, mse in scores.items() if np.isfinite(mse)]
    if not finite:
        raise EstimationError(
            f"the feedback model's initial estimate with a fed-back {block.kind} explodes in "
            "free-run simulation for every shape tried; try other orders (na, nb, nk) or "
            "another feedback block"
        )
    return models[min(finite, key=scores.__getitem__)], scores


def fit_feedback(
    data: Dataset,
    *,
    na: int,
    nb: int,
    nk: int = 1,
    r: int = 3,
    feedback_block: StaticBlock | None = None,
    max_nfev: int = MAX_NFEV,
    tail_fraction: float = TAIL_FRACTION,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
    center: bool = False,
) -> FitResult:
    """Identify a linear block with a static nonlinearity in feedback by free-run
    simulation error.

    .. math:: A(z^{-1}) y(k) = z^{-n_k} B(z^{-1}) [u(k) - \\textstyle\\sum_{m=2}^r c_m y(k)^m]

    Parameters
    ----------
    data : Dataset
        Estimation data, one input and one output.
    na, nb, nk : int
        Orders of the linear block (MATLAB convention, ``nk >= 1``).
    r : int, default 3
        Degree of the feedback polynomial (``c_2..c_r``; ``r = 1``: the output-error
        model without feedback).
    feedback_block : StaticBlock, optional
        Another block to feed back instead of the polynomial (``DeadZone(0, 0)``,
        ``Saturation.template()``, ``PiecewiseLinear.template(knots=7)``, a user's
        block; a polynomial here counts as ``r`` of its degree). Its starting form: the
        initial estimate searches its shapes (module docstring).
    max_nfev, tail_fraction, patience, ftol, xtol, gtol
        Of the refinement, see :func:`~blockid.fitting.simulation_error.refine`.
    center : bool, default False
        Fit around the mean operating point and keep the means as the model's offsets
        (``fit_model`` does this itself for the structure, by default).

    Returns
    -------
    FitResult
        As :func:`~blockid.fitting.simulation_error.refine` (``metrics_mode =
        "simulation"``), with ``settings`` also holding ``r``, ``feedback_block``,
        ``initial`` (the candidate that started the refinement), ``candidates`` (free-run
        MSE of each), ``center``; ``history["initial_seconds"]``.

    Examples
    --------
    A discrete Duffing oscillator simulated without noise is recovered:

    >>> import numpy as np
    >>> from blockid.blocks import Polynomial
    >>> from blockid.blocks.linear import LinearBlock
    >>> from blockid.data import Dataset
    >>> plant = LinearFeedback("u", "y", linear=LinearBlock(2, 1, 1, a=[-1.5, 0.7], b=[0.5]),
    ...                        feedback=Polynomial([0.0, 0.0, 0.8], constant=False))
    >>> u = np.random.default_rng(0).normal(0, 0.5, 2000)
    >>> data = Dataset.from_arrays(u, plant.simulate(u), ["u"], ["y"])
    >>> fit = fit_feedback(data, na=2, nb=1, nk=1, r=3)
    >>> np.allclose(fit.model.free_parameters(), plant.free_parameters())
    True
    """
    r = checked("r", r)  # the options' one declaration
    if feedback_block is not None and getattr(feedback_block, "role", None) != "static":
        raise ParameterError(
            f"feedback_block must be a static block (dead-zone, saturation, "
            f"piecewise-linear, ...), got {feedback_block!r}",
            parameter="feedback_block",
        )
    if feedback_block is not None and feedback_block.kind == Polynomial.kind:
        r, feedback_block = int(feedback_block.degree), None
    offsets = (0.0, 0.0)
    if center:
        offsets = (
            float(np.mean(np.concatenate([e.u[:, 0] for e in data.experiments]))),
            float(np.mean(np.concatenate([e.y[:, 0] for e in data.experiments]))),
        )
        data = data.shifted(*offsets)
    t0 = time.perf_counter()
    if feedback_block is None:
        start, scores = initial_feedback(data, na=na, nb=nb, nk=nk, r=int(r))
    else:
        start, scores = initial_feedback_block(data, na=na, nb=nb, nk=nk, block=feedback_block)
    origin = min(scores, key=lambda k: scores[k] if np.isfinite(scores[k]) else np.inf)
    t_initial = time.perf_counter() - t0
    result = refine(
        start,
        data,
        max_nfev=max_nfev,
        tail_fraction=tail_fraction,
        patience=patience,
        ftol=ftol,
        xtol=xtol,
        gtol=gtol,
    )
    model = result.model
    if center:  # ranges were recorded relative to zero offsets: they hold for these
        model = model.replace(
            input_offset=offsets[0], output_offset=offsets[1], ranges=model.ranges
        )
    return replace(
        result,
        model=model,
        settings={
            **result.settings,
            "r": int(r) if feedback_block is None else None,
            "feedback_block": model.feedback.kind,
            "initial": origin,
            "candidates": scores,
            "center": bool(center),
        },
        history={**result.history, "initial_seconds": t_initial},
    )
