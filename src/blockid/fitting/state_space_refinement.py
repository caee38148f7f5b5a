"""The free-run refinement of a (polynomial or block) state-space model: its problem,
its normal equations summed piece by piece, and early stopping on a held-back tail
(:func:`refine_state_space`); :mod:`blockid.fitting.state_space` fits with it.

**Refinement (output error).** Every entry of ``A, B, C, D`` and every experiment's
initial state are refined together by Levenberg-Marquardt on the free-run simulation
error (:mod:`blockid.fitting.levenberg_marquardt`), the Jacobian computed forward in
time by a compiled kernel (:mod:`blockid._kernels.state_space`) and summed into
``J^T J`` piece by piece (``state_space_rows`` samples, :mod:`blockid.config`), so a
long record never holds it whole; the kernel's column blocks and the tiles of
``J^T J`` run on every core the fit may use, the same result bit for bit with any
number of threads (:mod:`blockid.fitting.threads`; ``docs/performance.md`` has the
times).
The parameters are unique only up to the state basis; the damping keeps the steps
defined. A candidate with an eigenvalue of ``A`` outside the circle of radius
``1 - margin`` (:func:`~blockid.fitting.checks.stability_margin` of the data), or a
non-finite or exploding run, is rejected (the damping grows).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.defaults import PATIENCE, STATE_SPACE_NFEV, STATE_SPACE_TAIL, TOLERANCE
from blockid.errors import EstimationError, OrderError, ParameterError
from blockid.fitting.checks import margin_for
from blockid.fitting.levenberg_marquardt import EarlyStop, levenberg_marquardt, note_tail
from blockid.fitting.threads import NormalSums, kernel_threads, threads_for_fit
from blockid.models.state_space import PolynomialStateSpace

__all__ = ["MIN_HEAD", "NULL_SPACE", "TAIL_SAMPLES_PER_PARAMETER", "refine_state_space"]

#: Eigenvalues of the scaled ``J^T J`` below this fraction of the largest are the
#: directions the parameters are not unique in (the state basis): steps leave them.
NULL_SPACE = 1e-11
#: A run whose mean squared error exceeds this many times the output variance explodes.
_EXPLODE = 1e6


@dataclass(frozen=True)
class _Signals:
    """Normalised experiments and the normalisation."""

    u: list[np.ndarray]
    y: list[np.ndarray]
    input_offset: np.ndarray
    input_scale: np.ndarray
    output_offset: np.ndarray
    output_scale: np.ndarray


# ----------------------------------------------------------------------------- refinement
@dataclass
class _Tracker:
    nfev: int = 0
    njev: int = 0
    cost: list[float] = field(default_factory=list)
    # early stopping on the held-back tails (``refine_state_space``'s ``tail_fraction``)
    patience: int = 0
    tail: list[float] = field(default_factory=list)
    best_tail: float = np.inf
    best_theta: np.ndarray | None = None
    since_best: int = 0
    triggered: bool = False


@dataclass(frozen=True)
class _Tail:
    """An experiment's whole normalised record and where its fitted head ends."""

    u: np.ndarray
    y: np.ndarray
    n_fit: int


class _Problem:
    """Simulation error of a state-space model (polynomial, or with blocks:
    :class:`~blockid.models.state_space.ForwardSensitivities`) and its normal equations,
    over the model's free parameters (its ``parameter_mask``: ``D`` held at zero
    without a feedthrough) and every experiment's initial state."""

    def __init__(
        self, template: Any, sig: _Signals, feedthrough: bool, tails: list[_Tail] | None = None
    ):
        self.template = template
        self.sig = sig
        self.tails = tails or []
        self.margin = margin_for(max(len(u) for u in sig.u))
        full = template.free_parameters()
        self.free = template.parameter_mask(feedthrough)
        self.full = full
        self.n_model = int(self.free.sum())
        self.nx = template.nx
        self.tracker = _Tracker()
        y_all = np.concatenate([y.reshape(-1) for y in sig.y])
        self.size = y_all.size
        self.limit = _EXPLODE * (float(np.var(y_all)) + 1e-300)
        self.penalty = np.full(self.size, 2.0 * np.sqrt(self.limit))

    def split(self, theta: np.ndarray) -> tuple[PolynomialStateSpace | None, list[np.ndarray]]:
        x0s = [theta[self.n_model + e * self.nx : self.n_model + (e + 1) * self.nx]
               for e in range(len(self.sig.u))]  # fmt: skip
        if not np.all(np.isfinite(theta)):
            return None, x0s
        full = self.full.copy()
        full[self.free] = theta[: self.n_model]
        try:
            model = self.template.with_free_parameters(full)
        except (OrderError, ParameterError):  # a block refusing its parameters: rejected
            return None, x0s
        if not model.is_stable(self.margin):
            return None, x0s
        return model, x0s

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        self.tracker.nfev += 1
        model, x0s = self.split(theta)
        if model is None:
            return self.penalty
        parts = []
        with np.errstate(all="ignore"):
            for u, y, x0 in zip(self.sig.u, self.sig.y, x0s, strict=True):
                out = model.run(u, x0)[0]
                parts.append((y - out).reshape(-1))
        r = np.concatenate(parts)
        if not np.all(np.isfinite(r)) or float(np.mean(r**2)) > self.limit:
            return self.penalty
        return r

    def normal_equations(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``J^T J`` and ``J^T r`` summed piece by piece, on the threads the fit may
        use (:mod:`blockid.fitting.threads`: the same result with any number). A model
        that can walks only the columns it fits."""
        model, x0s = self.split(theta)
        assert model is not None, "the Jacobian is taken at accepted iterates only"
        self.monitor(theta, model, x0s)
        n_exp, nm, nx = len(self.sig.u), self.n_model, self.nx
        kept = np.r_[np.flatnonzero(self.free), self.full.size + np.arange(nx)]
        threads = threads_for_fit()
        ny = self.sig.y[0].shape[1]
        # two buffers for the pieces (one walked while the other's tiles are summed)
        piece_rows = get_config()["state_space_rows"]
        buffers = [np.empty((piece_rows * ny, kept.size)) for _ in range(2)]
        piece = 0
        with kernel_threads(threads), NormalSums(nm + nx * n_exp, threads) as sums:
            for e, (u, y, x0) in enumerate(zip(self.sig.u, self.sig.y, x0s, strict=True)):
                cols = np.r_[np.arange(nm), nm + e * nx + np.arange(nx)]
                own = model.selects_columns  # walks the kept columns alone, into a buffer
                carried = (
                    model._sensitivity_start(x0, kept) if own else model._sensitivity_start(x0)
                )
                for k0 in range(0, u.shape[0], piece_rows):
                    with np.errstate(all="ignore"):
                        if own:
                            sums.wait()  # the buffer about to be overwritten is free
                            out, J = model.jacobian_piece(u[k0 : k0 + piece_rows], *carried,
                                                          buffer=buffers[piece % 2])  # fmt: skip
                        else:
                            out, J = model.jacobian_piece(u[k0 : k0 + piece_rows], *carried)
                            J = J[:, kept]
                    sums.add(J, y[k0 : k0 + piece_rows] - out, cols)
                    piece += 1
            H, g = sums.result()
        self.tracker.njev += 1
        self.tracker.cost.append(sums.cost / self.size)
        return H, g

    def tail_mse(self, model: Any, x0s: list[np.ndarray]) -> float:
        """Free-run MSE (normalised) on the held-back tails, each experiment simulated
        whole from its fitted initial state (the tail starts from the model's own)."""
        errs = []
        for tail, x0 in zip(self.tails, x0s, strict=True):
            if tail.n_fit < tail.y.shape[0]:
                with np.errstate(all="ignore"):
                    out = model.run(tail.u, x0)[0]
                errs.append((tail.y[tail.n_fit :] - out[tail.n_fit :]).reshape(-1))
        err = np.concatenate(errs)
        return float(np.mean(err**2)) if np.all(np.isfinite(err)) else np.inf

    def monitor(self, theta: np.ndarray, model: Any, x0s: list[np.ndarray]) -> None:
        """Early stopping at an accepted iterate: the tails' error, the best iterate,
        and :class:`~blockid.fitting.levenberg_marquardt.EarlyStop` after ``patience``
        iterates without a better one."""
        tracker = self.tracker
        if not self.tails:
            return
        note_tail(tracker, self.tail_mse(model, x0s), theta)


def refine_state_space(
    model: Any,
    data: Dataset,
    *,
    initial_states: list[np.ndarray] | None = None,
    feedthrough: bool = True,
    max_nfev: int = STATE_SPACE_NFEV,
    tail_fraction: float = STATE_SPACE_TAIL,
    patience: int | None = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> tuple[PolynomialStateSpace, dict[str, Any]]:
    """Refine every parameter of ``model`` (``D`` held where it is without
    ``feedthrough``) and every experiment's initial state on the free-run simulation
    error (module docstring); returns the model and what the solver did. ``model`` is a
    (polynomial) state-space model or a block state-space model
    (:mod:`blockid.fitting.block_state_space`), within its ``parameter_bounds``.

    ``tail_fraction`` > 0: early stopping, as the chains' refinement
    (:mod:`blockid.fitting.simulation_error`), on a record of fewer than
    ``TAIL_SAMPLES_PER_PARAMETER`` output samples per refined unknown (a longer one is
    fitted whole: ``info["tail_fraction"]`` is 0). The last ``tail_fraction`` of every
    experiment long enough (a head of at least ``MIN_HEAD`` samples) is held back; the
    solver fits the heads, and at every accepted iterate each experiment is simulated
    whole from its fitted initial state and the error on its tail recorded. The iterate
    with the smallest tail error is returned, the start included (a refinement that
    lowers the error on the heads and raises it on the tails returns its start, and a
    warning says so); the solver stops after ``patience`` accepted iterates without a
    better tail (None: never).
    """
    u_all = [np.ascontiguousarray(model.normalised_input(e.u)) for e in data.experiments]
    y_all = [np.ascontiguousarray(model.normalised_output(e.y)) for e in data.experiments]
    n_unknowns = int(model.parameter_mask(feedthrough).sum()) + model.nx * len(u_all)
    long_record = sum(y.size for y in y_all) >= TAIL_SAMPLES_PER_PARAMETER * n_unknowns
    if long_record and tail_fraction > 0:
        tail_fraction = 0.0  # long enough not to fit the noise: nothing held back
    heads = [_head(u.shape[0], tail_fraction) for u in u_all]
    tails = (
        [_Tail(u, y, n) for u, y, n in zip(u_all, y_all, heads, strict=True)]
        if any(n < u.shape[0] for u, n in zip(u_all, heads, strict=True))
        else None
    )
    sig = _Signals(
        [np.ascontiguousarray(u[:n]) for u, n in zip(u_all, heads, strict=True)],
        [np.ascontiguousarray(y[:n]) for y, n in zip(y_all, heads, strict=True)],
        model.input_offset, model.input_scale, model.output_offset, model.output_scale,
    )  # fmt: skip
    if initial_states is None:
        initial_states = [model.initial_state(e.u, e.y[: 4 * model.nx]) for e in data.experiments]
    problem = _Problem(model, sig, feedthrough, tails)
    problem.tracker.patience = np.inf if patience is None else int(patience)
    theta0 = np.concatenate([model.free_parameters()[problem.free], *initial_states])
    r0 = problem.residuals(theta0)
    if r0 is problem.penalty:
        raise EstimationError(
            "the state-space start is unstable or its simulation explodes on the estimation "
            "data; no refinement is possible (try another order)"
        )
    t0 = time.perf_counter()
    bounds = (np.full(theta0.size, -np.inf), np.full(theta0.size, np.inf))
    low, high = model.parameter_bounds()  # a block's (a state-space block model)
    bounds[0][: problem.n_model] = low[problem.free]
    bounds[1][: problem.n_model] = high[problem.free]
    tracker = problem.tracker
    try:
        theta, reason = levenberg_marquardt(
            problem, theta0, bounds, max_nfev, ftol, xtol, gtol, null_space=NULL_SPACE
        )
    except EarlyStop:
        theta = tracker.best_theta
        reason = f"early stopping: no better tail error in {patience} accepted iteration(s)"
    earlier = tracker.triggered  # the best tail came before the last iterate
    if tails is not None and not tracker.triggered:
        last, x0s = problem.split(theta)  # the solver's last iterate is not yet monitored
        last_tail = np.inf if last is None else problem.tail_mse(last, x0s)
        if last_tail < tracker.best_tail:
            tracker.best_tail, tracker.best_theta = last_tail, theta.copy()
        if tracker.best_theta is not None:
            earlier = not np.array_equal(tracker.best_theta, theta)
            theta = tracker.best_theta
    fitted, _ = problem.split(theta)
    if fitted is None:  # pragma: no cover - the solver keeps accepted iterates only
        fitted = model
    r = problem.residuals(theta)
    info = {
        "stop_reason": reason,
        "patience": patience,
        "iterations": tracker.njev - 1,
        "function_evaluations": tracker.nfev,
        "initial_normalised_mse": float(np.mean(r0**2)),
        "final_normalised_mse": float(np.mean(r**2)),
        "seconds": time.perf_counter() - t0,
    }
    if long_record:
        info["tail_fraction"] = 0.0
        info["early_stopping_off"] = (
            f"{TAIL_SAMPLES_PER_PARAMETER} or more output samples per refined unknown "
            f"({n_unknowns}): nothing held back"
        )
    if tails is not None:
        info.update({
            "tail_fraction": float(tail_fraction),
            "early_stopping": tracker.triggered,
            "initial_tail_mse": tracker.tail[0] if tracker.tail else None,
            "tail_mse": float(tracker.best_tail),
            "best_tail_earlier": bool(earlier),
        })  # fmt: skip
        if tracker.tail and np.array_equal(theta, theta0):
            info["warnings"] = [
                "early stopping kept the start: no iterate of the refinement lowered the "
                f"free-run error on the held-back tails ({tail_fraction:g} of each "
                "experiment) below the start's, so the model is its start (for a linear "
                "state space: the subspace estimate; for a polynomial or block state "
                "space: its linear start with the nonlinear terms at their start); with more "
                "data, or tail_fraction=0 (--tail-fraction 0), the refinement runs to "
                "convergence"
            ]
    return fitted, info


#: Early stopping holds back no tail of an experiment whose head would be shorter.
MIN_HEAD = 100
#: Early stopping holds back nothing from a record of at least this many output samples
#: per refined unknown (parameters and initial states): there the refinement's excess
#: error from fitting the noise is of the order of 1 % (a least-squares fit's ``P / N``),
#: below what a fifth of the record held back costs (``docs/models.md``).
TAIL_SAMPLES_PER_PARAMETER = 100


def _head(n: int, tail_fraction: float) -> int:
    """Samples of an experiment of ``n`` fitted with ``tail_fraction`` held back."""
    head = n - int(round(tail_fraction * n))
    return head if head >= MIN_HEAD and head < n else n


def _solver_settings(info: dict[str, Any], max_nfev: int) -> dict[str, Any]:
    """What the (last) refinement did, at the top of ``settings`` as for every
    simulation-error fit."""
    return {
        "max_nfev": int(max_nfev),
        "tail_fraction": info.get("tail_fraction", 0.0),
        "patience": info.get("patience"),
        "iterations": info["iterations"],
        "function_evaluations": info["function_evaluations"],
        "initial_tail_mse": info.get("initial_tail_mse"),
        "tail_mse": info.get("tail_mse"),
        "early_stopping": bool(info.get("early_stopping", False)),
        "best_tail_earlier": bool(info.get("best_tail_earlier", False)),
        "stop_reason": info["stop_reason"],
    }
