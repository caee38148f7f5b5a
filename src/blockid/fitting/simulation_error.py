"""The default estimator of block-oriented models: minimise the free-run simulation error.

.. math::

    \\hat\\theta = \\arg\\min_\\theta \\sum_e \\sum_{k = n_0}^{N_e - 1}
        \\bigl(y_e(k) - \\hat y_e(k; \\theta)\\bigr)^2

where ``ŷ(k; θ)`` is the model's free-run simulation from the input alone
(:meth:`BlockModel.simulate`, started from the first ``n_0 = max_lag`` measured outputs
of each experiment, which are skipped) and ``θ`` are the identifiable parameters
(:meth:`BlockModel.free_parameters`: input block, ``a``, ``b`` without ``b_0``,
``q_2..``). This is what a user of the model needs (control design, benchmarks score
free-run simulation) and, unlike the papers' recursive key-term algorithms (B5, A8),
it converges: Gauss-Newton on a smooth least-squares problem from a nearby start.

Solver: ``scipy.optimize.least_squares`` (trust-region reflective, parameters scaled by
the Jacobian's column norms), with a semi-analytic Jacobian: the input block's
derivative (regressors of blocks linear in their parameters, branch derivatives of the
backlash (A3), dead zone and saturation) is filtered through the linear block together
with the ``a``/``b`` sensitivities in one compiled all-pole recursion
(:mod:`blockid._kernels.simulation`) and multiplied by ``N_2'(x)``; the first
``max_lag`` samples' dependence on ``q`` through ``x = N_2^{-1}(y)`` is included.

Long records: the Jacobian has one row per fitted sample. Above ``jacobian_bytes``
(:mod:`blockid.config`) it is not formed: :func:`sensitivity_chunks` walks the
chain in pieces (each linear block continues from the previous piece's last inputs and
outputs, exactly), ``J^T J`` and ``J^T r`` are summed piece by piece, and
Levenberg-Marquardt on these normal equations (:func:`_levenberg_marquardt`, same
column scaling, stopping rules and early stopping) replaces ``least_squares``. Memory
then stays a few copies of the data (5 million samples: docs/performance.md).
Squaring the condition number is harmless here: the columns are scaled to unit norm
and the problems have tens of parameters, not thousands. ``settings["solver"]`` says
which solver ran. Chains with a dynamic block (backlash) keep the whole Jacobian.

Stability is enforced by rejection, not by a reparameterisation: a candidate whose
linear block is unstable, whose parameters are invalid for its block (e.g. a negative
dead band), or whose simulation is not finite or exceeds ``10^6`` times the output
variance returns a constant residual vector whose cost is four times that bound, so the
trust-region step is rejected and the radius shrinks. The data of a stable plant put
the optimum strictly inside the stable region, where the penalty is never active, so
the minimiser is exactly the least-squares one (a stable reparameterisation, e.g. by
reflection coefficients, would change the geometry of the problem for nothing). The
Jacobian is only evaluated at accepted points, which are always stable. Bounds keep
backlash slopes positive and dead bands non-negative.

Early stopping: with ``tail_fraction > 0`` the last fraction of every experiment is
held out. The solver fits the first ``1 - tail_fraction`` of each experiment; at every
accepted iterate the free-run simulation error on the held-out tails is computed
(simulating each experiment from its start, so the tail starts from the model's own
state) and the iterate with the smallest tail error is kept. If the tail error has not
improved for ``patience`` accepted iterates, the solver stops ("early stopping
triggered"). With ``tail_fraction = 0`` the whole record is fitted and the solver's
final iterate is returned.

Two starts for Hammerstein-Wiener: the simulation error is not convex, and an H-W
model with the identity output block *is* the Hammerstein model. :func:`fit_simulation_error`
therefore refines H-W both from its initial estimate and from the refined Hammerstein
model (``q = [1, 0, ..]``) and keeps the result with the smaller free-run error on the
estimation data, so an H-W fit never ends worse than the Hammerstein fit it contains
(up to early stopping, which picks iterates by the held-out tail). On paper B's plant
each start wins on some seeds (``docs/reproduction.md``).

The result always passes :func:`~blockid.fitting.checks.check_model` (finite, stable,
free-run not worse than a linear ARX); a start or a result that is unstable,
non-finite or exploding raises :class:`~blockid.errors.EstimationError`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from blockid.blocks.base import Block
from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.defaults import DEGREE, MAX_NFEV, PATIENCE, TAIL_FRACTION, TOLERANCE
from blockid.errors import BlockidError, DataError, EstimationError, ParameterError
from blockid.fitting.checks import check_model, margin_for, refuse_unstable, simulation_mse
from blockid.fitting.initial import initial_estimate, resolve_structure
from blockid.fitting.levenberg_marquardt import EarlyStop, levenberg_marquardt, note_tail
from blockid.fitting.options import checked
from blockid.fitting.result import FitResult, simulation_result
from blockid.models.block import BlockModel, ChainModel, HammersteinWiener
from blockid.models.sensitivities import sensitivity_chunks

__all__ = [
    "NESTED_START",
    "chunkable",
    "fit_simulation_error",
    "refine",
    "sensitivity_chunks",
    "simulate_with_sensitivities",
]

METHOD = "simulation-error"

#: ``settings["solver"]`` of a refinement, by whether the problem was large.
SOLVERS = {
    False: "scipy.optimize.least_squares (trust-region reflective)",
    True: "Levenberg-Marquardt on the normal equations, in pieces (a long record)",
}

#: A candidate whose simulation MSE exceeds this multiple of the output variance is
#: treated as exploding (the bound :func:`check_model` uses).
_EXPLODE = 1e6


# ----------------------------------------------------------------------------- Jacobian
def simulate_with_sensitivities(
    model: Any, u: Any, y_initial: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """Free-run simulation and its parameter derivatives: the model's own
    ``simulate_with_sensitivities`` (a chain's is
    :func:`blockid.models.sensitivities.chain_sensitivities`)."""
    return model.simulate_with_sensitivities(u, y_initial)


# ----------------------------------------------------------------------------- problem
@dataclass
class _Segment:
    """One experiment: fitted on ``[n0, n_fit)``, monitored on ``[n_fit, N)``."""

    u: np.ndarray
    y: np.ndarray
    n_fit: int


@dataclass
class _Tracker:
    """What the solver has done so far, and the best iterate on the tail."""

    patience: int
    nfev: int = 0
    njev: int = 0
    best_theta: np.ndarray | None = None
    best_tail: float = np.inf
    since_best: int = 0
    triggered: bool = False
    cost: list[float] = field(default_factory=list)
    tail: list[float] = field(default_factory=list)
    accepted: np.ndarray | None = None  # the last accepted iterate


class _Problem:
    """Residuals ``y - ŷ`` on the fitted parts, and their Jacobian; see the module notes."""

    def __init__(self, template: BlockModel, segments: list[_Segment], tracker: _Tracker):
        self.template = template
        self.segments = segments
        self.tracker = tracker
        self.n0 = template.max_lag
        self.margin = margin_for(max(s.y.shape[0] for s in segments))
        y_fit = np.concatenate([s.y[self.n0 : s.n_fit] for s in segments])
        self.size = y_fit.size
        self.limit = _EXPLODE * (float(np.var(y_fit)) + 1e-300)  # MSE bound
        self.penalty = np.full(self.size, 2.0 * np.sqrt(self.limit))  # MSE 4x the bound
        self.has_tail = any(s.n_fit < s.y.shape[0] for s in segments)
        self._last: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros(0))
        # A chain with static blocks after its last linear block starts a simulation
        # from their inverse only where they are invertible over the ranges recorded on
        # the estimation data (and bends polynomials onto tangents beyond them): every
        # iterate records its own, as the delivered model will, so that the criterion
        # minimised is the one the returned model is scored on.
        last = getattr(template, "last_linear_index", None)
        self.ranged = last is not None and last < len(template.blocks) - 1
        self.experiments = [(s.u, s.y) for s in segments]
        self._ranged: tuple[np.ndarray, BlockModel] | None = None

    def model(self, theta: np.ndarray) -> BlockModel | None:
        """The model at ``theta`` (with its ranges on the estimation data where they
        decide its start), or None if ``theta`` is invalid or unstable."""
        if not np.all(np.isfinite(theta)):
            return None
        try:
            model = self.template.with_free_parameters(theta)
        except BlockidError:
            return None
        if not model.is_stable(self.margin):
            return None
        return self.with_ranges(model, theta)

    def with_ranges(self, model: BlockModel, theta: np.ndarray | None = None) -> BlockModel:
        """``model`` as the optimiser simulates it (see ``ranged``); the model of the
        last ``theta`` is kept, so the Jacobian at an accepted iterate does not record
        the ranges its residuals just recorded."""
        if not self.ranged:
            return model
        cached = self._ranged
        if theta is not None and cached is not None and np.array_equal(cached[0], theta):
            return cached[1]
        with np.errstate(all="ignore"):
            model = model.with_ranges(self.experiments)
        if theta is not None:
            self._ranged = (theta.copy(), model)
        return model

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        self.tracker.nfev += 1
        model = self.model(theta)
        if model is None:
            return self.penalty
        n0 = self.n0
        with np.errstate(all="ignore"):
            r = np.concatenate(
                [
                    s.y[n0 : s.n_fit] - model.simulate(s.u[: s.n_fit], s.y[:n0])[n0:, 0]
                    for s in self.segments
                ]
            )
            bad = not np.all(np.isfinite(r)) or float(np.mean(r**2)) > self.limit
        if bad:
            return self.penalty
        self._last = (theta.copy(), r)
        return r

    def jacobian(self, theta: np.ndarray) -> np.ndarray:
        """Jacobian at an accepted iterate; also the early-stopping monitor."""
        model = self.with_ranges(self.template.with_free_parameters(theta), theta)
        n0 = self.n0
        blocks = []
        for s in self.segments:
            _, dy = simulate_with_sensitivities(model, s.u[: s.n_fit], s.y[:n0])
            blocks.append(-dy[n0 : s.n_fit])
        J = np.vstack(blocks)
        self._monitor(theta, model)
        return J

    def normal_equations(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(J^T J, J^T r)`` at an accepted iterate, summed piece by piece
        (:func:`sensitivity_chunks`) so that ``J`` is never formed; also the
        early-stopping monitor."""
        model = self.with_ranges(self.template.with_free_parameters(theta), theta)
        n0, n = self.n0, theta.size
        H, g = np.zeros((n, n)), np.zeros(n)
        for s in self.segments:
            pieces = sensitivity_chunks(model, s.u[: s.n_fit], s.y[:n0])
            for start, y_hat, dy in pieces:
                skip = max(n0 - start, 0)  # the measured initial outputs are not fitted
                J = -dy[skip:]
                r = s.y[start + skip : start + y_hat.shape[0]] - y_hat[skip:]
                H += J.T @ J
                g += J.T @ r
        self._monitor(theta, model)
        return H, g

    def _monitor(self, theta: np.ndarray, model: BlockModel) -> None:
        """Book-keeping at an accepted iterate: the fitted MSE, and the tail error for
        early stopping (:func:`~blockid.fitting.levenberg_marquardt.note_tail` raises
        ``EarlyStop`` when it has not improved)."""
        tracker = self.tracker
        tracker.njev += 1
        tracker.accepted = theta.copy()
        last_theta, last_r = self._last
        if np.array_equal(last_theta, theta):  # the solver evaluates fun first
            tracker.cost.append(float(np.mean(last_r**2)))
        if self.has_tail:
            tail = self.tail_mse(model)
            note_tail(tracker, tail, theta)

    def tail_mse(self, model: BlockModel) -> float:
        """Free-run MSE on the held-out tails (each experiment simulated from its start)."""
        errs = []
        for s in self.segments:
            if s.n_fit < s.y.shape[0]:
                with np.errstate(all="ignore"):
                    sim = model.simulate(s.u, s.y[: self.n0])[s.n_fit :, 0]
                errs.append(s.y[s.n_fit :] - sim)
        err = np.concatenate(errs)
        return float(np.mean(err**2)) if np.all(np.isfinite(err)) else np.inf


class _FreeOffset:
    """A Wiener chain whose output offset is one more free parameter (the last).

    The output polynomial has no constant (B3), so a Wiener chain's constant is its
    output offset; fitted at the output's mean (centring) it is wrong wherever the
    polynomial's mean over the data is not zero (a square term: an exact Wiener plant
    was fitted 14 % off). Refined with the other parameters, it is the least-squares
    constant. Its derivative is 1 plus its effect through the simulation's start from
    the inverse of the first measured outputs, taken by a forward difference. Only
    where the whole Jacobian is formed (up to ``jacobian_bytes``, about 1 million
    samples of a Wiener model of 8 parameters): the piecewise path of longer records
    keeps the offset the fit started from.
    """

    def __init__(self, base: ChainModel) -> None:
        self.base = base

    def __getattr__(self, name: str) -> Any:
        return getattr(self.base, name)

    def free_parameters(self) -> np.ndarray:
        return np.append(self.base.free_parameters(), 0.0)

    def parameter_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lower, upper = self.base.parameter_bounds()
        return np.append(lower, -np.inf), np.append(upper, np.inf)

    def _shifted(self, model: ChainModel, delta: float) -> ChainModel:
        return model.replace(output_offset=model.output_offset + delta)

    def with_free_parameters(self, theta: Any) -> _FreeOffset:
        theta = np.asarray(theta, dtype=float)
        model = self.base.with_free_parameters(theta[:-1])
        return _FreeOffset(self._shifted(model, float(theta[-1])))

    def with_ranges(self, experiments: Any) -> _FreeOffset:
        return _FreeOffset(self.base.with_ranges(experiments))

    def replace(self, **changes: Any) -> _FreeOffset:
        return _FreeOffset(self.base.replace(**changes))

    def simulate_with_sensitivities(
        self, u: Any, y_initial: Any = None
    ) -> tuple[np.ndarray, np.ndarray]:
        y, dy = self.base.simulate_with_sensitivities(u, y_initial)
        h = 1e-6 * (1.0 + float(np.std(y)))
        shifted = self._shifted(self.base, h).replace(ranges=self.base.ranges)
        column = (shifted.simulate(u, y_initial)[:, 0] - y) / h
        return y, np.column_stack([dy, column])


def offset_is_free(model: Any) -> bool:
    """A chain of linear blocks then a polynomial output block without constant (a
    Wiener model): its output offset is refined (:class:`_FreeOffset`)."""
    if not isinstance(model, ChainModel):
        return False
    last = model.blocks[-1]
    before = model.blocks[: model.last_linear_index + 1]
    return (
        model.last_linear_index == len(model.blocks) - 2
        and getattr(last, "kind", None) == "polynomial"
        and not getattr(last, "constant", True)
        and all(b.role == "linear" for b in before)
    )


def chunkable(model: Any) -> bool:
    """Whether :func:`~blockid.models.sensitivities.sensitivity_chunks` can walk the
    model in pieces: a chain of static and linear blocks (a dynamic block such as a
    backlash starts from rest and is run over the whole record)."""
    return isinstance(model, ChainModel) and all(
        b.role in ("static", "linear") for b in model.blocks
    )


def _describe(model: ChainModel) -> dict[str, Any]:
    """Orders and block kinds of a model, for ``settings``."""
    out: dict[str, Any] = {}
    linear = model.linear_blocks
    for k, g in enumerate(linear, start=1):
        tag = str(k) if len(linear) > 1 else ""
        out.update({f"na{tag}": g.na, f"nb{tag}": g.nb, f"nk{tag}": g.nk})
    out["input_block"] = None if model.input_block is None else model.input_block.kind
    out["output_block"] = None if model.output_block is None else model.output_block.kind
    return out


def _segments(data: Dataset, n0: int, tail_fraction: float, n_par: int) -> list[_Segment]:
    """Split every experiment into a fitted head and a monitored tail.

    An experiment whose head would hold fewer than ``n_par`` samples keeps no tail.
    """
    segments = []
    for e in data.experiments:
        N = e.n_samples
        n_tail = int(round(tail_fraction * N))
        if N - n_tail - n0 < max(n_par, 1):  # too short to hold out a tail
            n_tail = 0
        segments.append(_Segment(np.ascontiguousarray(e.u[:, 0]), e.y[:, 0].copy(), N - n_tail))
    return segments


# ----------------------------------------------------------------------------- public
def refine(
    model: BlockModel,
    data: Dataset,
    *,
    max_nfev: int = MAX_NFEV,
    tail_fraction: float = TAIL_FRACTION,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Refine any block-oriented model by minimising its free-run simulation error.

    This is ``--refine`` after any other method, and the second half of
    :func:`fit_simulation_error`. See the module docstring for the method.

    Parameters
    ----------
    model : BlockModel
        Starting model (its structure, orders, blocks and offsets are kept). Its
        linear block must be stable.
    data : Dataset
        Estimation data; the model's input and output names must be in it.
    max_nfev : int, default 200
        Limit on residual evaluations (each one free-run simulation of the data).
    tail_fraction : float, default 0.2
        Fraction at the end of every experiment held out for early stopping (0 to fit
        everything and switch early stopping off).
    patience : int, default 5
        Accepted iterates without a better tail error before early stopping.
    ftol, xtol, gtol : float
        Tolerances of ``scipy.optimize.least_squares``.

    Returns
    -------
    FitResult
        ``settings`` records ``iterations`` (accepted steps), ``function_evaluations``,
        ``initial_simulation_mse``/``final_simulation_mse`` (free run on all the
        estimation data), ``initial_tail_mse``/``tail_mse``, ``early_stopping``
        (whether it triggered) and the solver's ``stop_reason``; ``history`` holds the
        fitted MSE and the tail MSE per accepted iterate and ``seconds`` the solver's
        wall time. ``estimation_metrics`` are free-run (``metrics_mode="simulation"``).

    Raises
    ------
    EstimationError
        If the start is unstable, not finite or its simulation explodes, or if the
        result fails :func:`~blockid.fitting.checks.check_model`.
    """
    if not isinstance(model, ChainModel) and not hasattr(model, "simulate_with_sensitivities"):
        raise ParameterError(
            f"refinement on simulation error works on block-oriented models, got "
            f"{type(model).__name__}; fit an ARX model with method batch instead"
        )
    tail_fraction = checked("tail_fraction", tail_fraction)  # the options' one declaration
    max_nfev, patience = checked("max_nfev", max_nfev), checked("patience", patience)
    if tuple(data.inputs) != model.inputs or tuple(data.outputs) != model.outputs:
        raise DataError(
            f"the model maps {list(model.inputs)} to {list(model.outputs)} but the data have "
            f"inputs {list(data.inputs)} and outputs {list(data.outputs)}; select those signals"
        )
    # Optimise the model as it simulates the estimation data: the ranges recorded on
    # earlier data (a warm start) would bound inversions and bend polynomial blocks onto
    # their tangents; the result records its own ranges on these data at the end.
    model = model.replace(ranges=None)
    # the offset's derivative needs the whole Jacobian: on a record too long for it
    # (the piecewise path below) the offset stays where it is
    rows = sum(max(e.n_samples - model.max_lag, 0) for e in data.experiments)
    n_free = model.free_parameters().size + 1
    # (above jacobian_bytes of Jacobian, blockid.config: the normal equations in pieces,
    # so memory stays a few copies of the data; a dynamic block keeps the whole Jacobian)
    whole_bytes = get_config()["jacobian_bytes"]
    free_offset = offset_is_free(model) and rows * n_free * 8 <= whole_bytes
    if free_offset:
        model = _FreeOffset(model)
    theta0 = model.free_parameters()
    n_par = theta0.size
    data.check_orders(model.max_lag, n_par, what=f"{model.structure} model")
    if not np.all(np.isfinite(theta0)):
        raise EstimationError(
            "refinement cannot start: the starting model's parameters are not finite"
        )
    refuse_unstable(
        model,
        data,
        "refinement cannot start: the starting model's linear block is unstable or "
        "beyond the stability margin (largest pole magnitude {rho:.10g}, limit "
        "{limit:.10g} on these data: 0.999, or 1 - 1/n on an experiment of "
        "n > 1000 samples), so its simulation error is not defined or not allowed. "
        "Start from the default initial estimate (method simulation-error) instead, "
        "or refine on a record longer than the pole's time constant",
    )
    t_start = time.perf_counter()
    tracker = _Tracker(patience=int(patience))
    segments = _segments(data, model.max_lag, float(tail_fraction), n_par)
    problem = _Problem(model, segments, tracker)
    r0 = problem.residuals(theta0)
    if r0 is problem.penalty:
        raise EstimationError(
            "refinement cannot start: the starting model's free-run simulation is not "
            "finite or explodes on the estimation data. Start from the default initial "
            "estimate (method simulation-error) instead"
        )
    initial_mse = simulation_mse(problem.with_ranges(model), data)
    initial_tail = problem.tail_mse(problem.with_ranges(model)) if problem.has_tail else None

    lower, upper = model.parameter_bounds()
    stop_reason, theta = "", theta0
    large = problem.size * n_par * 8 > whole_bytes and chunkable(model)
    try:
        with np.errstate(all="ignore"):
            if large:
                theta, stop_reason = levenberg_marquardt(
                    problem, theta0, (lower, upper), int(max_nfev), ftol, xtol, gtol
                )
            else:
                sol = least_squares(
                    problem.residuals,
                    theta0,
                    jac=problem.jacobian,
                    bounds=(lower, upper),
                    method="trf",
                    x_scale="jac",
                    ftol=ftol,
                    xtol=xtol,
                    gtol=gtol,
                    max_nfev=int(max_nfev),
                )
                theta = sol.x
                stop_reason = "max_nfev reached" if sol.status == 0 else sol.message
    except EarlyStop:
        stop_reason = f"early stopping: no better tail error in {patience} accepted iteration(s)"
    if problem.has_tail and tracker.best_theta is not None:
        theta = tracker.best_theta
    fitted = model.with_free_parameters(theta)
    if free_offset:
        fitted, model = fitted.base, model.base
    # The estimation ranges decide whether a simulation may start from N_2^{-1} of the
    # measured outputs; record them first, so that every MSE reported here (and the
    # choice between starts) is the one evaluate() gives for the returned model.
    fitted = fitted.with_ranges([(e.u, e.y) for e in data.experiments])
    elapsed = time.perf_counter() - t_start
    metrics = check_model(fitted, data, METHOD)
    settings: dict[str, Any] = {
        **_describe(fitted),
        "max_nfev": int(max_nfev),
        "tail_fraction": float(tail_fraction),
        "patience": int(patience),
        "iterations": max(tracker.njev - 1, 0),
        "function_evaluations": tracker.nfev,
        "initial_simulation_mse": initial_mse,
        "final_simulation_mse": simulation_mse(fitted, data),
        "initial_tail_mse": initial_tail,
        "tail_mse": tracker.best_tail if problem.has_tail else None,
        "early_stopping": tracker.triggered,
        "stop_reason": stop_reason,
        "solver": SOLVERS[large],
    }
    if problem.has_tail and tracker.best_theta is not None and np.array_equal(theta, theta0):
        settings["warnings"] = [
            "early stopping kept the start: no iterate lowered the error on the held-out "
            f"tail ({tail_fraction:g} of each experiment) below the initial estimate's, so "
            "the model is that initial estimate (for output-error: the least-squares ARX "
            "start), not a refined one; with more data, or tail_fraction=0 "
            "(--tail-fraction 0), the refinement runs to convergence"
        ]
    history = {
        "fit_mse": np.array(tracker.cost),
        "tail_mse": np.array(tracker.tail),
        "seconds": elapsed,
    }
    return simulation_result(fitted, data, METHOD, settings, metrics, history)


def fit_simulation_error(
    data: Dataset,
    structure: str | type[BlockModel],
    *,
    na: int | None = None,
    nb: int | None = None,
    nk: int | None = None,
    r1: int = DEGREE,
    r2: int = DEGREE,
    initial: BlockModel | None = None,
    input_block: Block | None = None,
    output_block: Block | None = None,
    max_nfev: int = MAX_NFEV,
    tail_fraction: float = TAIL_FRACTION,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Identify a block-oriented model by minimising its free-run simulation error.

    The default method for Hammerstein, Wiener, Hammerstein-Wiener and backlash models:
    :func:`~blockid.fitting.initial.initial_estimate` (unless ``initial`` is given),
    then :func:`refine`.

    Parameters
    ----------
    data : Dataset
        Estimation data, one input and one output. For the default two-segment input
        block (B1) the input should take both signs and span the operating range.
    structure : str or type
        ``"hammerstein"``, ``"wiener"``, ``"hammerstein-wiener"`` or ``"backlash"``.
    na, nb, nk : int
        Orders of the linear block (MATLAB convention); required unless ``initial``
        is given (then they must match it).
    r1, r2 : int, default 3
        Orders of the default input block (B1) and the output polynomial (B3).
    initial : BlockModel, optional
        Starting model instead of the initial estimate.
    input_block, output_block : Block, optional
        Templates of the blocks (kind and form; see ``initial_estimate``).
    max_nfev, tail_fraction, patience, ftol, xtol, gtol
        See :func:`refine`.

    Returns
    -------
    FitResult
        As :func:`refine`, with ``settings["initial"]`` saying where it started and
        ``history["initial_seconds"]`` the time the initial estimate took. A
        Hammerstein-Wiener fit without ``initial`` is refined from two starts (the
        initial estimate and the refined Hammerstein model with the identity output
        block, :data:`NESTED_START`; not with ``r2 = 1``, where the two models are the
        same) and keeps the one with the smaller free-run MSE on the estimation data;
        ``settings["starts"]`` gives both MSEs (or the error of a start that failed).

    Examples
    --------
    A Hammerstein-Wiener plant (B1-B3) simulated without noise is recovered exactly:

    >>> import numpy as np
    >>> from blockid.blocks import Polynomial, TwoSegmentPolynomial
    >>> from blockid.data import Dataset
    >>> from blockid.models import HammersteinWiener
    >>> plant = HammersteinWiener(
    ...     "u", "y", input_block=TwoSegmentPolynomial([0.1, 1.0, 0.5], [-0.2, -0.4, 0.3]),
    ...     output_block=Polynomial([1.0, 0.2], constant=False),
    ...     na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[1.0, 0.4])
    >>> u = np.random.default_rng(0).uniform(-1, 1, 1000)
    >>> data = Dataset.from_arrays(u, plant.simulate(u), ["u"], ["y"])
    >>> fit = fit_simulation_error(data, "hammerstein-wiener", na=2, nb=2, nk=1, r1=2, r2=2)
    >>> np.allclose(fit.model.free_parameters(), plant.free_parameters(), atol=1e-8)
    True
    >>> [round(q, 6) for q in fit.model.parameters["q"]], fit.settings["early_stopping"]
    ([1.0, 0.2], False)
    """
    cls = resolve_structure(structure)
    t0 = time.perf_counter()
    if initial is None:
        if na is None or nb is None or nk is None:
            raise ParameterError(
                "give the orders na, nb and nk (or a starting model initial=)", parameter="na"
            )
        start = initial_estimate(
            data,
            cls,
            na=na,
            nb=nb,
            nk=nk,
            r1=r1,
            r2=r2,
            input_block=input_block,
            output_block=output_block,
        )
        origin = "initial estimate"
    else:
        if not isinstance(initial, cls):
            raise ParameterError(
                f"initial must be a {cls.__name__} model, got {type(initial).__name__}"
            )
        for name, value in (("na", na), ("nb", nb), ("nk", nk)):
            if value is not None and value != getattr(initial, name):
                raise ParameterError(
                    f"{name}={value} does not match the starting model's {name}="
                    f"{getattr(initial, name)}; drop {name} or change the model"
                )
        start, origin = initial, "given model"
    t_initial = time.perf_counter() - t0
    options = dict(
        max_nfev=max_nfev,
        tail_fraction=tail_fraction,
        patience=patience,
        ftol=ftol,
        xtol=xtol,
        gtol=gtol,
    )
    if initial is not None or not issubclass(cls, HammersteinWiener):
        result = refine(start, data, **options)
        return replace(
            result,
            settings={**result.settings, "initial": origin},
            history={**result.history, "initial_seconds": t_initial},
        )
    return _best_hammerstein_wiener(data, start, t_initial, r1, input_block, options)


#: Where a Hammerstein-Wiener fit started, by ``settings["initial"]``.
NESTED_START = "refined Hammerstein model (q = identity)"


def _best_hammerstein_wiener(
    data: Dataset,
    start: BlockModel,
    t_initial: float,
    r1: int,
    input_block: Block | None,
    options: dict[str, Any],
) -> FitResult:
    """Refine H-W from its initial estimate and from the refined nested Hammerstein.

    A Hammerstein-Wiener model with the identity output block is the Hammerstein model,
    so the refined Hammerstein model is a second start from which the H-W fit cannot
    end worse than the Hammerstein fit. The simulation error is not convex: on paper B's
    plant each start wins on some data. The result with the smaller free-run MSE on the
    whole estimation record is returned; ``settings["starts"]`` lists both.
    """
    t0 = time.perf_counter()
    results: dict[str, FitResult] = {}
    failures: dict[str, str] = {}
    try:
        results["initial estimate"] = refine(start, data, **options)
    except EstimationError as exc:
        failures["initial estimate"] = str(exc)
    identity = start.output_block.identity()
    # with r2 = 1 the H-W model is the Hammerstein model: one start is enough
    if identity is not None and start.output_block.free_mask(True).any():
        try:
            nested = fit_simulation_error(
                data,
                "hammerstein",
                na=start.na,
                nb=start.nb,
                nk=start.nk,
                r1=r1,
                input_block=input_block,
                **options,
            ).model
        except BlockidError as exc:  # e.g. an input block the Hammerstein class does not take
            failures[NESTED_START] = f"the Hammerstein fit to start from failed: {exc}"
        else:
            nested_start = start.with_blocks((*nested.blocks, identity), ranges=None)
            try:
                results[NESTED_START] = refine(nested_start, data, **options)
            except EstimationError as exc:
                failures[NESTED_START] = str(exc)
    if not results:
        raise EstimationError(
            "the Hammerstein-Wiener fit failed from every start ("
            + "; ".join(f"{k}: {v}" for k, v in failures.items())
            + "). Try other orders (na, nb, nk, r1, r2), data that excite the plant more "
            "(the input should cross the whole operating range, both signs for B1), or a "
            "simpler structure"
        )
    origin = min(results, key=lambda k: results[k].settings["final_simulation_mse"])
    result = results[origin]
    starts = {
        k: {"final_simulation_mse": r.settings["final_simulation_mse"]} for k, r in results.items()
    }
    starts.update({k: {"error": v} for k, v in failures.items()})
    return replace(
        result,
        settings={**result.settings, "initial": origin, "starts": starts},
        history={
            **result.history,
            "initial_seconds": t_initial,
            "seconds": time.perf_counter() - t0,
        },
    )
