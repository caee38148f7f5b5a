"""Wiener-Hammerstein models from the best linear approximation (BLA).

.. math::

    x = z^{-n_k} \\frac{B_1}{A_1} u, \\qquad v = N(x) = \\sum_{m=0}^{r} c_m x^m,
    \\qquad y = \\frac{B_2}{A_2} v, \\qquad c_1 = 1,\\ b_{2,0} = 1

The method of Sjöberg and Schoukens (Automatica 48, 2012), as blockid implements it:

1. **BLA**: a linear output-error model ``z^-nk B/A`` of the given orders, fitted by
   minimising its free-run simulation error (from a least-squares ARX start). For a
   Wiener-Hammerstein system driven by Gaussian-like noise its poles and zeros are those
   of ``G_1`` and ``G_2`` together.
2. **Splits**: the BLA's poles and zeros are grouped into units (a real root, or a
   complex-conjugate pair) and every assignment of units to ``G_1`` or ``G_2`` is a
   candidate; the delay stays in ``G_1`` and ``G_2`` has ``n_k = 0``.
3. **Cheap score of every split**: with ``G_1`` and ``G_2`` fixed the model is linear in
   ``c``: ``y = sum_m c_m G_2(x^m)``, ``x = G_1 u``. One least-squares solve per split
   gives ``c`` and the free-run simulation error of that Wiener-Hammerstein model
   (exactly: the regressors are simulated from rest).
4. **Refinement**: the best ``starts`` splits are normalised (``b_{2,0} = 1``, the
   linear coefficient of ``N`` moved into ``G_1``) and refined by the simulation-error
   fit (:func:`blockid.fitting.simulation_error.refine`, which differentiates any chain
   of blocks); the refined model with the smallest free-run error on the estimation
   data wins.

The data should be centred (the structure's ``center`` default does that); the
polynomial's constant term carries what is left of an operating point.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import replace
from typing import Any

import numpy as np

from blockid.blocks import Polynomial
from blockid.blocks.linear import LinearBlock
from blockid.data.dataset import Dataset
from blockid.defaults import MAX_NFEV, PATIENCE, TAIL_FRACTION, TOLERANCE
from blockid.errors import BlockidError, EstimationError, OrderError, ParameterError
from blockid.estimators import BatchLeastSquares
from blockid.fitting.checks import margin_for, simulation_mse, stability_margin
from blockid.fitting.initial import _stabilise
from blockid.fitting.result import FitResult
from blockid.fitting.simulation_error import refine
from blockid.models.block import ChainModel, WienerHammerstein

__all__ = ["best_linear_approximation", "fit_wiener_hammerstein", "split_candidates"]

#: Largest number of splits scored (the units of larger BLAs are enumerated up to it).
MAX_SPLITS = 4096
#: Samples used to score the splits (the first ones of each experiment).
SCORE_SAMPLES = 50_000


def _order(name: str, value: Any, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise OrderError(f"{name} must be a whole number >= {low}, got {value!r}")
    return int(value)


def _arx(u: list[np.ndarray], y: list[np.ndarray], na: int, nb: int, nk: int):
    """Least-squares ARX ``(a, b)`` with RMS-scaled columns (QR)."""
    n0 = max(na, nk + nb - 1, 1)
    rows, targets = [], []
    for ui, yi in zip(u, y, strict=True):
        N = yi.shape[0]
        cols = [-yi[n0 - j : N - j] for j in range(1, na + 1)]
        cols += [ui[n0 - nk - i : N - nk - i] for i in range(nb)]
        rows.append(np.column_stack(cols))
        targets.append(yi[n0:])
    Phi, target = np.vstack(rows), np.concatenate(targets)
    scale = np.sqrt(np.mean(Phi**2, axis=0))
    scale[scale == 0] = 1.0
    theta = BatchLeastSquares().fit(Phi / scale, target).coef_ / scale
    return _stabilise(theta[:na], margin_for(max(len(x) for x in y))), theta[na:]


def best_linear_approximation(
    data: Dataset, na: int, nb: int, nk: int, *, max_nfev: int = 100
) -> LinearBlock:
    """The output-error linear model ``z^-nk B/A`` of the data (step 1 above)."""
    u = [e.u[:, 0] for e in data.experiments]
    y = [e.y[:, 0] for e in data.experiments]
    a, b = _arx(u, y, na, nb, nk)
    start = ChainModel(data.inputs, data.outputs, [LinearBlock(na, nb, nk, a, b)])
    try:
        fit = refine(start, data, max_nfev=max_nfev, tail_fraction=0.0)
    except EstimationError:
        return start.linear  # the ARX start is the best linear model we have
    return fit.model.linear


def _units(roots: np.ndarray) -> list[np.ndarray]:
    """Real roots alone, complex roots with their conjugates."""
    units, used = [], np.zeros(roots.size, dtype=bool)
    for i, r in enumerate(roots):
        if used[i]:
            continue
        used[i] = True
        if abs(r.imag) <= 1e-9 * max(1.0, abs(r)):
            units.append(np.array([r.real]))
            continue
        rest = np.flatnonzero(~used)
        j = rest[np.argmin(np.abs(roots[rest] - np.conj(r)))] if rest.size else None
        if j is None:
            units.append(np.array([r.real]))
            continue
        used[j] = True
        units.append(np.array([r, np.conj(r)]))
    return units


def _poly(roots: list[np.ndarray]) -> np.ndarray:
    """``[1, c_1, ..]`` of ``prod (1 - r z^-1)``, real."""
    flat = np.concatenate(roots) if roots else np.zeros(0)
    return np.real(np.poly(flat)) if flat.size else np.ones(1)


def split_candidates(bla: LinearBlock) -> list[tuple[LinearBlock, LinearBlock]]:
    """Every assignment of the BLA's pole and zero units to ``(G_1, G_2)`` (step 2).

    ``G_1`` keeps the delay and unit gain of ``B_1``'s leading coefficient; ``G_2`` has
    ``n_k = 0`` and ``b_0 = 1``. At most :data:`MAX_SPLITS` splits.
    """
    poles = _units(bla.poles())
    b = np.trim_zeros(bla.b, "f")
    zeros = _units(np.roots(b) if b.size > 1 else np.zeros(0))
    out = []
    for pole_mask in itertools.product((0, 1), repeat=len(poles)):
        for zero_mask in itertools.product((0, 1), repeat=len(zeros)):
            p1 = [p for p, m in zip(poles, pole_mask, strict=True) if m == 0]
            p2 = [p for p, m in zip(poles, pole_mask, strict=True) if m == 1]
            z1 = [z for z, m in zip(zeros, zero_mask, strict=True) if m == 0]
            z2 = [z for z, m in zip(zeros, zero_mask, strict=True) if m == 1]
            a1, a2, b1, b2 = _poly(p1)[1:], _poly(p2)[1:], _poly(z1), _poly(z2)
            g1 = LinearBlock(a1.size, b1.size, bla.nk, a1, b1)
            g2 = LinearBlock(a2.size, b2.size, 0, a2, b2)
            out.append((g1, g2))
            if len(out) >= MAX_SPLITS:
                return out
    return out


def _score(
    g1: LinearBlock, g2: LinearBlock, u: list[np.ndarray], y: list[np.ndarray], degree: int
) -> tuple[float, np.ndarray, float]:
    """Free-run MSE of the best polynomial for this split, its ``c``, and the scale of x."""
    xs = [g1.simulate(ui) for ui in u]
    sx = float(np.sqrt(np.mean(np.concatenate(xs) ** 2))) or 1.0
    cols = []
    for m in range(degree + 1):
        cols.append(np.concatenate([g2.simulate((xi / sx) ** m) for xi in xs]))
    R = np.column_stack(cols)
    target = np.concatenate(y)
    if not np.all(np.isfinite(R)):
        return np.inf, np.zeros(degree + 1), sx
    scale = np.sqrt(np.mean(R**2, axis=0))
    scale[scale == 0] = 1.0
    try:
        c = BatchLeastSquares().fit(R / scale, target).coef_ / scale
    except BlockidError:
        return np.inf, np.zeros(degree + 1), sx
    return float(np.mean((target - R @ c) ** 2)), c, sx


def _normalised(
    data: Dataset, g1: LinearBlock, g2: LinearBlock, c: np.ndarray, sx: float
) -> WienerHammerstein | None:
    """The split as a normalised model: ``N`` with linear coefficient 1 (into ``G_1``)."""
    if not abs(c[1]) > 1e-12 * max(np.max(np.abs(c)), 1e-300):
        return None
    gain = c[1] / sx  # x' = c_1 x / sx
    q = c / c[1] ** np.arange(c.size)
    first = LinearBlock(g1.na, g1.nb, g1.nk, g1.a, g1.b * gain)
    return WienerHammerstein(
        data.inputs,
        data.outputs,
        first=first,
        static=Polynomial(q, constant=True),
        second=g2,
        sampling_time=data.sampling_time,
    )


def fit_wiener_hammerstein(
    data: Dataset,
    *,
    na: int = 6,
    nb: int = 7,
    nk: int = 0,
    r2: int = 5,
    starts: int = 3,
    max_nfev: int = MAX_NFEV,
    tail_fraction: float = TAIL_FRACTION,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Identify a Wiener-Hammerstein model from the BLA's split (module docstring).

    Parameters
    ----------
    data : Dataset
        Estimation data, one input and one output (centred: see module docstring).
    na, nb, nk : int
        Orders of the BLA, shared out between the two linear blocks.
    r2 : int, default 5
        Degree of the static polynomial (with a constant term).
    starts : int, default 3
        Best splits refined by the simulation-error fit.
    max_nfev, tail_fraction, patience, ftol, xtol, gtol
        Of the refinement (:func:`~blockid.fitting.simulation_error.refine`).

    Returns
    -------
    FitResult
        ``settings`` records the BLA's simulation MSE, the number of splits scored and
        every refined start's MSE.

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.blocks import LinearBlock, Polynomial
    >>> from blockid.data import Dataset
    >>> from blockid.models import WienerHammerstein
    >>> plant = WienerHammerstein("u", "y", first=LinearBlock(1, 1, 1, [-0.8], [0.5]),
    ...     static=Polynomial([0.0, 1.0, 0.0, -0.3]), second=LinearBlock(1, 2, 0, [-0.5], [1, 0.4]))
    >>> u = np.random.default_rng(0).standard_normal(3000)
    >>> data = Dataset.from_arrays(u, plant.simulate(u), ["u"], ["y"])
    >>> fit = fit_wiener_hammerstein(data, na=2, nb=2, nk=1, r2=3, tail_fraction=0.0)
    >>> bool(fit.settings["final_simulation_mse"] < 1e-12)
    True
    """
    na = _order("na", na, 1)
    nb = _order("nb", nb, 1)
    nk = _order("nk", nk, 0)
    r2 = _order("r2", r2, 1)
    starts = _order("starts", starts, 1)
    if data.n_inputs != 1 or data.n_outputs != 1:
        raise ParameterError("a Wiener-Hammerstein model has one input and one output")
    t0 = time.perf_counter()
    bla = best_linear_approximation(data, na, nb, nk)
    u = [e.u[:SCORE_SAMPLES, 0] for e in data.experiments]
    y = [e.y[:SCORE_SAMPLES, 0] for e in data.experiments]
    scored = []
    for g1, g2 in split_candidates(bla):
        mse, c, sx = _score(g1, g2, u, y, r2)
        if np.isfinite(mse):
            scored.append((mse, g1, g2, c, sx))
    scored.sort(key=lambda s: s[0])
    options = dict(
        max_nfev=max_nfev,
        tail_fraction=tail_fraction,
        patience=patience,
        ftol=ftol,
        xtol=xtol,
        gtol=gtol,
    )
    results: list[tuple[float, FitResult]] = []
    failures = []
    for _, g1, g2, c, sx in scored[:starts]:
        model = _normalised(data, g1, g2, c, sx)
        if model is None or not model.is_stable(stability_margin(data)):
            continue
        try:
            fit = refine(model, data, **options)
        except EstimationError as exc:
            failures.append(str(exc))
            continue
        results.append((fit.settings["final_simulation_mse"], fit))
    if not results:
        raise EstimationError(
            "the Wiener-Hammerstein fit failed from every split of the BLA"
            + (f" ({failures[0]})" if failures else "")
            + ". Try other BLA orders (na, nb, nk), another degree r2, or a simpler structure"
        )
    results.sort(key=lambda r: r[0])
    best = results[0][1]
    bla_model = ChainModel(data.inputs, data.outputs, [bla])
    settings = {
        **best.settings,
        "bla": {"na": na, "nb": nb, "nk": nk, "simulation_mse": simulation_mse(bla_model, data)},
        "splits_scored": len(scored),
        "starts": [r[0] for r in results],
        "r2": r2,
    }
    return replace(
        best,
        settings=settings,
        history={**best.history, "seconds": time.perf_counter() - t0},
    )
