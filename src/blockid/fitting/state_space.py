"""Linear state-space models by subspace identification, refined on simulation error;
polynomial nonlinear state-space models (PNLSS) started from them.

**Subspace (PO-MOESP, Verhaegen & Dewilde 1992; the CVA weighting of Van Overschee &
De Moor 1996).** On normalised signals, block Hankel matrices of ``s`` past and ``s``
future inputs and outputs are stacked (the columns of every experiment side by side)
and reduced by one LQ factorisation (a QR of the transpose, accumulated ``state_space_rows``
columns at a time (:mod:`blockid.config`), so memory stays a few copies of the data):

.. math::

    \\begin{bmatrix} U_f \\\\ W_p \\\\ Y_f \\end{bmatrix} =
    \\begin{bmatrix} L_{11} & & \\\\ L_{21} & L_{22} & \\\\ L_{31} & L_{32} & L_{33}
    \\end{bmatrix} Q^T, \\qquad W_p = \\begin{bmatrix} U_p \\\\ Y_p \\end{bmatrix}

``L_32`` is the part of the future outputs that the past explains once the future inputs
are removed; its column space is that of the extended observability matrix ``Γ_s``.
``weighting="moesp"`` takes the SVD of ``L_32``; ``"cva"`` that of ``W L_32`` with ``W``
the inverse square root of the covariance of ``Y_f`` given ``U_f`` (canonical
correlations: singular values between 0 and 1). ``Γ_s = W^{-1} U_n S_n^{1/2}``, ``C`` its
first block row, ``A`` from its shift invariance by least squares; ``B``, ``D`` and every
experiment's initial state by linear least squares on the outputs (the simulated
response is linear in them). An unstable eigenvalue of ``A`` (possible on short or
noisy records) is reflected into the unit circle before ``B`` and ``D`` are fitted.

**Order.** Unless ``nx`` is given, the order is where the canonical correlations between
past and future (the CVA singular values, whatever the weighting of the estimate) drop
most: ``argmax_n log(σ_n / σ_{n+1})`` over ``n = 1 .. max_order``. Being scale-free they
separate the states from the noise and the nonlinearity more cleanly than MOESP's
singular values (on a mildly nonlinear second-order plant: 0.9997, 0.986, 0.43 against
1.59, 0.35, 0.095, where the MOESP gap reads one state); ``settings`` records both.

**Refinement (output error)**: :mod:`blockid.fitting.state_space_refinement`.

**The PNLSS's order.** Unless ``nx`` is given, :func:`fit_polynomial_state_space`
chooses it by what matters, the free-run error on data a model never saw: linear models
of order ``1, 2, ...`` are fitted on each half of the estimation data (two contiguous
folds, :func:`~blockid.data.folds.fold_plan`) and simulated over the other half from the
state its first outputs give; the order is the smallest whose pooled error (each output
over its spread) is within ``ORDER_TIE`` of the best, the scan stopping two orders past
the last one that beat the best by more than that (or at ``max_order``). The
canonical-correlation gap reads the linear dynamics' order; on a nonlinear plant it can
read the nonlinearity as states (the Silverbox: six, against the two of its documented
PNLSS). A linear score cannot see states that only the nonlinear terms use (WH 2009:
orders 4 to 6 within 0.2 %, chosen 4, where the degree-3 model needs 6).
``docs/orders.md`` has the table on three benchmark sets.

**PNLSS.** :func:`fit_polynomial_state_space` starts from the refined linear model
(``E = F = 0``: the start is the best linear approximation, so the fit never ends worse
than it) and refines every parameter with the monomials of degree 2 to ``degree``
added, and constant terms in both equations (the nonlinear terms move the operating
point). The monomials' arguments are clipped to the range the linear start's states and
the input span, widened by ``margin`` of it on each side: fixed for the whole fit, they
are the model's bounds (:class:`~blockid.models.state_space.PolynomialStateSpace`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from blockid._kernels import writable
from blockid._kernels.state_space import pnlss_simulate
from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.defaults import (
    MAX_ORDER,
    PATIENCE,
    PNLSS_NFEV,
    STATE_SPACE_NFEV,
    STATE_SPACE_TAIL,
    TIE,
    TOLERANCE,
    WEIGHTING,
)
from blockid.errors import DataError, EstimationError, OrderError, ParameterError
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.checks import refuse_unstable, stability_margin
from blockid.fitting.options import checked
from blockid.fitting.result import FitResult, simulation_result
from blockid.fitting.state_space_refinement import (
    _Signals,
    _solver_settings,
    refine_state_space,
)
from blockid.models.state_space import PolynomialStateSpace, StateSpace, monomial_exponents

__all__ = [
    "continue_polynomial_state_space",
    "fit_polynomial_state_space",
    "fit_state_space",
    "fit_subspace",
    "order_by_validation",
    "refine_state_space",
    "signal_statistics",
    "subspace",
]

#: Orders whose cross-validated error is within this fraction of the best are ties, the
#: smallest chosen (the structure search's ``tie``, :data:`blockid.defaults.TIE`).
ORDER_TIE = TIE


# ----------------------------------------------------------------------------- signals
def _normalised(data: Dataset) -> _Signals:
    u_off, u_sc, y_off, y_sc = signal_statistics(data)
    return _Signals(
        [np.ascontiguousarray((e.u - u_off) / u_sc) for e in data.experiments],
        [np.ascontiguousarray((e.y - y_off) / y_sc) for e in data.experiments],
        u_off, u_sc, y_off, y_sc,
    )  # fmt: skip


def signal_statistics(data: Dataset) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Means and spreads of the inputs and outputs over every experiment, refusing a
    signal that never moves and inputs that move together (each named)."""
    u_all = np.vstack([e.u for e in data.experiments])
    y_all = np.vstack([e.y for e in data.experiments])
    u_off, y_off = u_all.mean(axis=0), y_all.mean(axis=0)
    u_sc, y_sc = u_all.std(axis=0), y_all.std(axis=0)
    for names, scale, mean, what in (
        (data.inputs, u_sc, u_off, "input"),
        (data.outputs, y_sc, y_off, "output"),
    ):
        for name, s, m in zip(names, scale, mean, strict=True):
            if not s > 1e-12 * max(1.0, abs(m)):  # a constant's spread is rounding only
                raise DataError(
                    f"{what} '{name}' is constant over the estimation data; a state-space "
                    "model needs every signal to vary (choose another range or column)"
                )
    if data.n_inputs > 1:
        _check_independent_inputs((u_all - u_off) / u_sc, data.inputs)
    return u_off, u_sc, y_off, y_sc


#: Smallest singular value, relative to the largest, of the standardised inputs below
#: which the inputs count as collinear (their effects cannot be told apart).
COLLINEAR = 1e-6


def _check_independent_inputs(u: np.ndarray, names: list[str]) -> None:
    """Refuse inputs that are (nearly) linear combinations of each other over the record,
    naming them: B's columns of such inputs are not identifiable, and a subspace fit
    would split their effect arbitrarily."""
    _, sv, vt = np.linalg.svd(u, full_matrices=False)
    if sv[-1] > COLLINEAR * sv[0]:
        return
    v = np.abs(vt[-1])
    involved = [n for n, w in zip(names, v, strict=True) if w > 0.1 * v.max()]
    raise DataError(
        f"inputs {', '.join(repr(n) for n in involved)} are (nearly) linear combinations "
        "of each other over the estimation data (smallest singular value of the "
        f"standardised inputs {sv[-1] / sv[0]:.1e} of the largest): a model cannot tell "
        "their effects apart; drop one of these columns, or use data where they move "
        "independently"
    )


def _model(data: Dataset, sig: _Signals, A, B, C, D, **extra: Any) -> PolynomialStateSpace:
    cls = PolynomialStateSpace if extra.get("exponents") is not None else StateSpace
    return cls(
        data.inputs, data.outputs, A, B, C, D,
        input_offset=sig.input_offset, input_scale=sig.input_scale,
        output_offset=sig.output_offset, output_scale=sig.output_scale,
        sampling_time=data.sampling_time, **extra,
    )  # fmt: skip


# ----------------------------------------------------------------------------- subspace
def _hankel(x: np.ndarray, start: int, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix: block row ``i`` holds ``x[start + i : start + i + cols].T``."""
    m = x.shape[1]
    out = np.empty((rows * m, cols))
    for i in range(rows):
        out[i * m : (i + 1) * m] = x[start + i : start + i + cols].T
    return out


def _lq(sig: _Signals, s: int) -> np.ndarray:
    """``L`` of the LQ factorisation of ``[1; U_f; U_p; Y_p; Y_f]``, accumulated by
    columns. The row of ones comes first, so that every later block is taken relative
    to its mean over the columns: an offset between the output's and the input's means
    (an operating point the linear model does not pass through) would otherwise look
    like a state with a pole at 1."""
    m, l = sig.u[0].shape[1], sig.y[0].shape[1]
    size = 2 * s * (m + l) + 1
    R = np.zeros((0, size))
    used, piece = 0, get_config()["state_space_rows"]
    for u, y in zip(sig.u, sig.y, strict=True):
        j = u.shape[0] - 2 * s + 1
        for c0 in range(0, max(j, 0), piece):
            c = min(piece, j - c0)
            block = np.vstack(
                (np.ones((1, c)), _hankel(u, s + c0, s, c), _hankel(u, c0, s, c),
                 _hankel(y, c0, s, c), _hankel(y, s + c0, s, c))
            )  # fmt: skip
            R = np.linalg.qr(np.vstack((R, block.T)), mode="r")
            used += c
    if used < size:
        raise DataError(
            f"subspace identification with horizon {s} needs at least {size + 2 * s - 1} "
            f"samples in one experiment; the data have {max(len(u) for u in sig.u)}: give "
            "more data or a smaller horizon / order"
        )
    return R.T / np.sqrt(used)


def _stable(A: np.ndarray, margin: float) -> np.ndarray:
    """``A`` with eigenvalues outside radius ``1 - margin`` reflected inside
    (``λ -> (1 - 2 margin)/λ̄``)."""
    lam, V = np.linalg.eig(A)
    bad = np.abs(lam) >= 1.0 - margin
    if not bad.any():
        return A
    lam = np.where(bad, 1.0 / np.conj(lam) * (1.0 - 2 * margin), lam)
    lam = np.where(np.abs(lam) >= 1.0 - margin, lam * 0.99, lam)
    return np.real(V @ np.diag(lam) @ np.linalg.inv(V))


def _bd_x0(
    A: np.ndarray, C: np.ndarray, sig: _Signals, feedthrough: bool
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], np.ndarray]:
    """``B``, ``D``, each experiment's ``x(0)`` and an output bias (the operating point's
    offset that the means leave) by least squares on the outputs."""
    nx, m, l = A.shape[0], sig.u[0].shape[1], C.shape[0]
    n_exp = len(sig.u)
    n_b, n_d = nx * m, (l * m if feedthrough else 0)
    n_theta = n_b + n_d + nx * n_exp + l
    rows, targets = [], []
    zero_e, zero_f = np.zeros((nx, 0)), np.zeros((l, 0))
    no_expo = np.zeros((0, nx + 1), dtype=np.int64)
    lims = np.full(nx + 1, np.inf)

    def response(B1: np.ndarray, u1: np.ndarray, x0: np.ndarray) -> np.ndarray:
        out = np.zeros((u1.shape[0], l))
        pnlss_simulate(writable(A), writable(B1), writable(C), np.zeros((l, 1)), zero_e, zero_f,
                       no_expo, -lims, lims, writable(u1), x0, out)  # fmt: skip
        return out

    for e, (u, y) in enumerate(zip(sig.u, sig.y, strict=True)):
        N = u.shape[0]
        phi = np.zeros((N, l, n_theta))
        for i in range(m):  # B[r, i]: the response to input i entering state r
            for r in range(nx):
                Br = np.zeros((nx, 1))
                Br[r, 0] = 1.0
                phi[:, :, r * m + i] = response(Br, u[:, [i]], np.zeros(nx))
        if feedthrough:
            for i in range(l):
                for j in range(m):
                    phi[:, i, n_b + i * m + j] = u[:, j]
        for r in range(nx):  # the free response to x(0) = e_r
            x0 = np.zeros(nx)
            x0[r] = 1.0
            phi[:, :, n_b + n_d + e * nx + r] = response(np.zeros((nx, 1)), np.zeros((N, 1)), x0)
        for i in range(l):
            phi[:, i, n_theta - l + i] = 1.0
        rows.append(phi.reshape(N * l, n_theta))
        targets.append(y.reshape(-1))
    theta = np.linalg.lstsq(np.vstack(rows), np.concatenate(targets), rcond=None)[0]
    B = theta[:n_b].reshape(nx, m)
    D = theta[n_b : n_b + n_d].reshape(l, m) if feedthrough else np.zeros((l, m))
    x0s = [theta[n_b + n_d + e * nx : n_b + n_d + (e + 1) * nx] for e in range(n_exp)]
    return B, D, x0s, theta[n_theta - l :]


@dataclass(frozen=True)
class SubspaceResult:
    """A subspace estimate: the model, the singular values, the order and how chosen."""

    model: StateSpace
    singular_values: np.ndarray
    nx: int
    horizon: int
    initial_states: list[np.ndarray] = field(default_factory=list)
    correlations: np.ndarray = field(default_factory=lambda: np.zeros(0))


def order_from_singular_values(sv: np.ndarray, max_order: int) -> int:
    """``argmax_n log(σ_n / σ_{n+1})`` over ``n = 1 .. max_order`` (module docstring).

    >>> order_from_singular_values(np.array([5.0, 3.0, 1e-3, 9e-4, 8e-4]), 4)
    2
    """
    k = min(max_order, sv.size - 1)
    if k < 1:
        return 1
    s = np.maximum(sv[: k + 1], 1e-300)
    return int(np.argmax(np.log(s[:-1] / s[1:]))) + 1


def subspace(
    data: Dataset,
    *,
    nx: int | None = None,
    max_order: int = MAX_ORDER,
    horizon: int | None = None,
    weighting: str = WEIGHTING,
    feedthrough: bool = False,
) -> SubspaceResult:
    """Linear state-space model by subspace identification (module docstring).

    Parameters
    ----------
    data : Dataset
        Estimation data, any number of inputs, outputs and experiments.
    nx : int, optional
        Model order; by default chosen from the singular values.
    max_order : int
        Largest order the singular-value rule considers.
    horizon : int, optional
        Past and future horizon ``s`` (default ``max(nx or max_order, 5) + 5``): more than
        the order, and enough samples per column to average the noise.
    weighting : {"moesp", "cva"}
    feedthrough : bool
        Estimate ``D`` (a direct term from input to output); off by default, as for
        sampled plants with a hold.
    """
    if weighting not in ("moesp", "cva"):
        raise ParameterError(f"weighting={weighting!r}: choose moesp or cva", parameter="weighting")
    top = nx if nx is not None else max_order
    if top < 1:
        raise OrderError(f"the state-space order must be >= 1, got {top}")
    sig = _normalised(data)
    m, l = sig.u[0].shape[1], sig.y[0].shape[1]
    s = horizon if horizon is not None else max(top, 5) + 5
    if s * l < top + 1:
        s = (top + 1 + l - 1) // l + 1
    L = _lq(sig, s)
    r1, r2 = 1 + s * m, 1 + s * (2 * m + l)
    L32 = L[r2:, r1:r2]
    # CVA: W the inverse square root of the covariance of Y_f given U_f; its singular
    # values are the canonical correlations between the past and the future outputs
    rest = L[r2:, r1:]
    w_val, w_vec = np.linalg.eigh(rest @ rest.T)
    w_val = np.maximum(w_val, 1e-12 * max(float(w_val.max()), 1e-300))
    W_cva = w_vec @ np.diag(w_val**-0.5) @ w_vec.T
    correlations = np.linalg.svd(W_cva @ L32, compute_uv=False)
    if weighting == "cva":
        W, W_inv = W_cva, w_vec @ np.diag(w_val**0.5) @ w_vec.T
    else:
        W = W_inv = np.eye(L32.shape[0])
    U, sv, _ = np.linalg.svd(W @ L32, full_matrices=False)
    limit = min(max_order, s * l - 1)
    n = nx if nx is not None else order_from_singular_values(correlations, limit)
    if n > min(sv.size, s * l - 1):
        raise OrderError(
            f"order {n} needs a horizon of more than {n} output samples; raise the horizon"
        )
    gamma = W_inv @ U[:, :n] * np.sqrt(sv[:n])
    C = gamma[:l]
    A = np.linalg.lstsq(gamma[:-l], gamma[l:], rcond=None)[0]
    A = _stable(A, stability_margin(data))
    B, D, x0s, bias = _bd_x0(A, C, sig, feedthrough)
    sig = replace(sig, output_offset=sig.output_offset + bias * sig.output_scale, y=[
        np.ascontiguousarray(y - bias) for y in sig.y])  # fmt: skip
    model = _model(data, sig, A, B, C, D)
    return SubspaceResult(model, sv, n, s, x0s, correlations)


# ----------------------------------------------------------------------------- public
def _check(model: PolynomialStateSpace, data: Dataset, method: str) -> dict[str, dict[str, float]]:
    """Finite, stable, a finite free run on the estimation data; its metrics."""
    if not np.all(np.isfinite(model.free_parameters())):
        raise EstimationError(f"{method} diverged: the parameter estimates are not finite")
    refuse_unstable(
        model,
        data,
        "{method} returned an unstable state matrix, or one beyond the stability "
        "margin (largest eigenvalue magnitude {rho:.10g}, limit {limit:.10g}); "
        "no model is returned: try another order",
        method=method,
    )
    ys, sims = [], []
    for e in data.experiments:
        with np.errstate(all="ignore"):
            sim = model.simulate(e.u, e.y[: model.max_lag])
        ys.append(e.y[model.max_lag :])
        sims.append(sim[model.max_lag :])
    y, sim = np.vstack(ys), np.vstack(sims)
    if not np.all(np.isfinite(sim)):
        raise EstimationError(
            f"{method} returned a model whose free-run simulation of the estimation data is "
            "not finite; no model is returned"
        )
    return metrics_by_output(y, sim, data.outputs)


def fit_state_space(
    data: Dataset,
    *,
    nx: int | None = None,
    max_order: int = MAX_ORDER,
    horizon: int | None = None,
    weighting: str = WEIGHTING,
    feedthrough: bool = False,
    refine: bool = True,
    max_nfev: int = STATE_SPACE_NFEV,
    tail_fraction: float = STATE_SPACE_TAIL,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Linear state-space model: subspace estimate, then (``refine``) output error.

    Parameters are those of :func:`subspace` and of :func:`refine_state_space`
    (``tail_fraction``, ``patience``: early stopping on a held-back tail of each
    experiment, by default 20 % and 5 iterates).

    Returns
    -------
    FitResult
        ``settings`` holds the order, how it was chosen, the horizon, the weighting, the
        singular values and what the refinement did; ``metrics_mode = "simulation"``.

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.data import Dataset
    >>> plant = StateSpace(["u"], ["y"], A=[[0.9, 0.2], [-0.2, 0.9]], B=[[1.0], [0.0]],
    ...                    C=[[1.0, 0.5]], D=[[0.0]])
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> fit = fit_state_space(Dataset.from_arrays(u, plant.simulate(u)), refine=False)
    >>> fit.settings["nx"], np.round(np.sort(np.abs(fit.model.poles())), 6).tolist()
    (2, [0.921954, 0.921954])
    """
    t0 = time.perf_counter()
    sub = subspace(
        data, nx=nx, max_order=max_order, horizon=horizon, weighting=weighting,
        feedthrough=feedthrough,
    )  # fmt: skip
    model: PolynomialStateSpace = sub.model
    settings: dict[str, Any] = {
        "nx": sub.nx,
        "order_from": "given" if nx is not None else "canonical correlations (largest log gap)",
        "horizon": sub.horizon,
        "weighting": weighting,
        "feedthrough": feedthrough,
        "singular_values": [float(v) for v in sub.singular_values[: 2 * max(sub.nx, max_order)]],
        "canonical_correlations": [
            float(v) for v in sub.correlations[: 2 * max(sub.nx, max_order)]
        ],
    }
    method = "subspace"
    if refine:
        model, info = refine_state_space(
            model, data, initial_states=sub.initial_states, feedthrough=feedthrough,
            max_nfev=max_nfev, tail_fraction=tail_fraction, patience=patience, ftol=ftol,
            xtol=xtol, gtol=gtol,
        )  # fmt: skip
        settings.update(_solver_settings(info, max_nfev))
        settings["refinement"] = info
        if info.get("warnings"):
            settings["warnings"] = list(info["warnings"])
        method = "subspace+simulation-error"
    metrics = _check(model, data, method)
    return _result(model, data, method, settings, metrics, t0)


def fit_subspace(
    data: Dataset,
    *,
    nx: int | None = None,
    max_order: int = MAX_ORDER,
    horizon: int | None = None,
    weighting: str = WEIGHTING,
    feedthrough: bool = False,
) -> FitResult:
    """The subspace estimate alone (:func:`fit_state_space` with ``refine=False``)."""
    return fit_state_space(
        data, nx=nx, max_order=max_order, horizon=horizon, weighting=weighting,
        feedthrough=feedthrough, refine=False,
    )  # fmt: skip


def with_observed_range(model: PolynomialStateSpace, data: Dataset) -> PolynomialStateSpace:
    """``model`` with the range its ``z = [x; u_n]`` covers on ``data`` (each experiment
    from the state its first outputs give) recorded for the extrapolation checks."""
    lower, upper = _observed_range(model, data)
    return model.replace(observed_lower=lower, observed_upper=upper)


def _observed_range(model: PolynomialStateSpace, data: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest ``z = [x; u_n]`` of ``model`` run over ``data``, each
    experiment from the state its first outputs give."""
    z = []
    for e in data.experiments:
        x0 = model.initial_state(e.u, e.y[: 4 * model.nx])
        z.append(np.hstack((model.states(e.u, x0), model.normalised_input(e.u))))
    zz = np.vstack(z)
    return zz.min(axis=0), zz.max(axis=0)


def order_by_validation(
    data: Dataset, max_order: int, **linear: Any
) -> tuple[int | None, list[dict[str, Any]]]:
    """The state dimension among ``1 .. max_order`` whose linear model
    (:func:`fit_state_space` with the options ``linear``) simulates held-back data best
    (module docstring: ties to the smallest order), and each order's scores; None (and
    no scores) when the data are too short for two folds of a few dozen samples."""
    from blockid.data.folds import fold_plan, materialise

    try:
        plan = fold_plan(data, 2, min_samples=60)
    except DataError:
        return None, []
    spread = np.maximum(np.vstack([e.y for e in data.experiments]).std(axis=0), 1e-300)
    scores: list[dict[str, Any]] = []
    best, gained = None, 0
    for n in range(1, max_order + 1):
        squares, count, folds = 0.0, 0, []
        try:
            for fold in plan.folds:
                train, test = materialise(data, fold.train), materialise(data, fold.test)
                model = fit_state_space(train, nx=n, **linear).model
                fold_sq, fold_n = 0.0, 0
                for e in test.experiments:
                    start = min(50, e.n_samples // 4)
                    with np.errstate(all="ignore"):
                        sim = model.simulate(e.u, e.y[:start])
                    err = ((e.y[start:] - sim[start:]) / spread).ravel()
                    fold_sq, fold_n = fold_sq + float(err @ err), fold_n + err.size
                squares, count = squares + fold_sq, count + fold_n
                folds.append(float(np.sqrt(fold_sq / max(fold_n, 1))))
        except (EstimationError, OrderError, DataError) as exc:
            scores.append({"nx": n, "error": None, "reason": str(exc)})
            break  # a higher order fails as well, or later
        rmse = float(np.sqrt(squares / max(count, 1)))
        scores.append({"nx": n, "error": rmse if np.isfinite(rmse) else None, "folds": folds})
        if np.isfinite(rmse) and (best is None or rmse < best[1]):
            if best is None or rmse * (1 + ORDER_TIE) < best[1]:
                gained = n  # the last order that beat the best by more than a tie
            best = (n, rmse)
        if best is not None and n >= gained + 2:
            break
    if best is None:
        return None, scores
    limit = (1 + ORDER_TIE) * best[1]
    chosen = min(s["nx"] for s in scores if s.get("error") is not None and s["error"] <= limit)
    return chosen, scores


def fit_polynomial_state_space(
    data: Dataset,
    *,
    nx: int | None = None,
    degree: int = 3,
    monomials: str = "full",
    max_order: int = MAX_ORDER,
    horizon: int | None = None,
    weighting: str = WEIGHTING,
    feedthrough: bool = False,
    margin: float = 0.25,
    start_degree: int | None = None,
    rung_nfev: int | None = None,
    max_nfev: int = PNLSS_NFEV,
    tail_fraction: float = STATE_SPACE_TAIL,
    patience: int | None = None,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Polynomial nonlinear state-space model started from the best linear one.

    Parameters
    ----------
    data : Dataset
    nx, max_order, horizon, weighting, feedthrough
        Of the linear start (:func:`fit_state_space`); without ``nx`` the order is
        chosen on held-back halves of the data (:func:`order_by_validation`, among
        ``1 .. max_order``).
    degree : int
        Largest total degree of the monomials (2 to 5; 1 gives the linear model).
    monomials : {"full", "states", "inputs"}
        Of which variables the monomials are (:func:`monomial_exponents`).
    margin : float
        Widening of the monomials' clipping range beyond the linear start's states and the
        input, as a fraction of each range's width on each side.
    start_degree : int, optional
        Fit degree by degree: the monomials up to ``start_degree`` refined from the
        linear start, then each degree up to ``degree`` refined from the model of the
        degree below (its coefficients kept, the new monomials' starting at zero): a
        continuation that reaches a better optimum than all monomials at once where the
        start is far from it (``docs/models.md``). Default: ``degree`` (one rung).
    rung_nfev : int, optional
        Limit on the simulations of each degree above ``start_degree`` (default
        ``max_nfev``): a rung of many more parameters that starts near its optimum.
    tail_fraction : float
        Held back at the end of each experiment for early stopping (every refinement:
        the order's, the linear start's, each degree's; :func:`refine_state_space`);
        0 fits everything to convergence.
    patience : int, optional
        Of the nonlinear refinement: accepted iterates without a better tail error
        before it stops. Default None, never: the refinement crawls through plateaus
        where the tail does not improve for tens of iterations (the Silverbox: about
        90) before it finds the nonlinearity; the iterate with the best tail is
        returned all the same. The linear start stops after ``PATIENCE``.
    max_nfev, ftol, xtol, gtol
        Of each refinement (the linear start's and each degree's). The nonlinear
        refinement crawls along curved valleys for a few hundred evaluations before it
        converges (the Silverbox: 342), hence a larger default than the linear fit's.
    """
    degree, margin = checked("degree", degree), checked("margin", margin)  # one declaration
    first = degree if start_degree is None else max(2, checked("start_degree", start_degree))
    rung_nfev = max_nfev if rung_nfev is None else checked("rung_nfev", rung_nfev)
    if first > degree:
        raise ParameterError(
            f"start_degree={start_degree} is above degree={degree}: the fit climbs from "
            "start_degree up to degree; give start_degree <= degree",
            parameter="start_degree",
        )
    t0 = time.perf_counter()
    # the options of the linear fits: those that choose the order and the linear start
    linear_options: dict[str, Any] = dict(
        horizon=horizon, weighting=weighting, feedthrough=feedthrough, max_nfev=max_nfev,
        tail_fraction=tail_fraction, patience=PATIENCE, ftol=ftol, xtol=xtol, gtol=gtol,
    )  # fmt: skip
    order_scores: list[dict[str, Any]] | None = None
    if nx is None:
        nx, order_scores = order_by_validation(data, max_order, **linear_options)
    linear = fit_state_space(data, nx=nx, max_order=max_order, **linear_options)
    if order_scores:
        linear = replace(linear, settings={
            **linear.settings,
            "order_from": "cross-validated linear models (2 folds, smallest within "
                          f"{ORDER_TIE:.0%} of the best free-run error)",
            "order_scores": order_scores,
        })  # fmt: skip
    start = linear.model
    n = start.nx
    if degree == 1:
        return linear
    expo = monomial_exponents(n, len(data.inputs), first, monomials, constant=True)
    lo, hi = _observed_range(start, data)
    span = np.maximum(hi - lo, 1e-12)
    template = PolynomialStateSpace(
        start.inputs, start.outputs, start.A, start.B, start.C, start.D,
        np.zeros((n, expo.shape[0])), np.zeros((len(data.outputs), expo.shape[0])), expo,
        lower=lo - margin * span, upper=hi + margin * span,
        input_offset=start.input_offset, input_scale=start.input_scale,
        output_offset=start.output_offset, output_scale=start.output_scale,
        sampling_time=start.sampling_time,
    )  # fmt: skip
    refine = dict(feedthrough=feedthrough, tail_fraction=tail_fraction, patience=patience,
                  ftol=ftol, xtol=xtol, gtol=gtol)  # fmt: skip
    model, info, limit, rungs = template, {}, max_nfev, []
    for d in range(first, degree + 1):
        limit = max_nfev if d == first else rung_nfev
        model, info = _rung(model, data, d, d > first, monomials, limit, refine)
        rungs.append({"degree": d, **_solver_settings(info, limit)})
    expo = model.exponents
    model = with_observed_range(model, data)
    own = {
        "linear_refinement": linear.settings.get("refinement"),
        "degree": degree,
        "monomials": monomials,
        "n_monomials": int(expo.shape[0]),
        "margin": margin,
        "start_degree": first,
        **({"rungs": rungs} if len(rungs) > 1 else {}),
    }
    return _refined_from_linear(
        model, data, "subspace+polynomial-state-space", linear, info, limit, own, t0
    )


def _refined_from_linear(
    model: Any,
    data: Dataset,
    method: str,
    linear: FitResult,
    info: dict[str, Any],
    limit: int,
    own: dict[str, Any],
    t0: float,
) -> FitResult:
    """The result of a model refined from the linear fit ``linear`` (the PNLSS's and the
    block state-space model's): its free run checked; its settings those of the linear
    fit (less its refinement), of the solver (at most ``limit`` simulations), the
    model's ``own``, the refinement ``info`` and the linear fit's metrics; the linear
    start's warnings, then the refinement's."""
    metrics = _check(model, data, method)
    settings = {
        **{k: v for k, v in linear.settings.items() if k != "refinement"},
        **_solver_settings(info, limit),
        **own,
        "refinement": info,
        "linear_simulation_metrics": linear.estimation_metrics,
    }
    notes = [f"the linear start: {w}" for w in linear.settings.get("warnings", [])]
    notes += info.get("warnings", [])
    if notes:
        settings["warnings"] = notes
    return _result(model, data, method, settings, metrics, t0)


def _result(
    model: Any, data: Dataset, method: str, settings: dict[str, Any], metrics: Any, t0: float
) -> FitResult:
    """A state-space fit's result: its metrics are of the free run (``_check``), its
    history the seconds since ``t0``."""
    return simulation_result(
        model, data, method, settings, metrics, {"seconds": time.perf_counter() - t0}
    )


def _rung(
    model: PolynomialStateSpace,
    data: Dataset,
    d: int,
    new: bool,
    monomials: str,
    limit: int,
    refine: dict[str, Any],
) -> tuple[PolynomialStateSpace, dict[str, Any]]:
    """One rung of the climb: the monomials of degree ``d`` added (``new``: the model has
    those below, kept), then every parameter refined with at most ``limit``
    simulations."""
    if new:
        expo = monomial_exponents(model.nx, len(data.inputs), d, monomials, constant=True)
        model = model.with_monomials(expo)
    return refine_state_space(model, data, max_nfev=limit, **refine)


def continue_polynomial_state_space(
    model: PolynomialStateSpace, data: Dataset, done: int, **options: Any
) -> FitResult:
    """:func:`fit_polynomial_state_space` ``(data, **options)`` of a climb
    (``start_degree`` below ``degree``) continued from ``model``, its fit up to degree
    ``done`` on the same data (the result of the same options with ``degree=done``, and
    without ``start_degree`` and ``rung_nfev`` when ``done`` is the start): only the rungs
    above ``done`` are refined, so the model is the one the whole climb gives, bit for
    bit, without its first rungs fitted again (``identify``'s climb on a fold whose lower
    degree it has fitted). Its settings are the last rung's."""
    import inspect

    bound = inspect.signature(fit_polynomial_state_space).bind(data, **options)
    bound.apply_defaults()
    o = bound.arguments
    first = max(2, int(o["start_degree"] if o["start_degree"] is not None else o["degree"]))
    if not first <= done < o["degree"]:
        raise ParameterError(
            f"a climb from degree {first} to {o['degree']} continues from a degree in "
            f"{first}..{o['degree'] - 1}, not {done}",
            parameter="start_degree",
        )
    limit = o["max_nfev"] if o["rung_nfev"] is None else o["rung_nfev"]
    refine = {k: o[k] for k in ("feedthrough", "tail_fraction", "patience", "ftol", "xtol", "gtol")}
    t0 = time.perf_counter()
    info: dict[str, Any] = {}
    for d in range(done + 1, o["degree"] + 1):
        model, info = _rung(model, data, d, True, o["monomials"], limit, refine)
    model = with_observed_range(model, data)
    method = "subspace+polynomial-state-space"
    metrics = _check(model, data, method)
    settings = {
        **_solver_settings(info, limit),
        "degree": o["degree"],
        "monomials": o["monomials"],
        "start_degree": first,
        "continued_from_degree": done,
        "refinement": info,
    }
    if info.get("warnings"):
        settings["warnings"] = list(info["warnings"])
    return _result(model, data, method, settings, metrics, t0)
