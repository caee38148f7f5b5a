"""The pass driver shared by the papers' recursive fitters (B4–B5, A6–A8).

Paper B's key-term RLS (:mod:`blockid.fitting.key_term`) and paper A's AW-RLS
(:mod:`blockid.fitting.backlash`) are one skeleton: run a compiled recursion over every
experiment on normalised signals, repeat passes until ``theta`` settles, check the
linear block after every pass, map ``theta`` back to the data's units, read the model
back and check it. What differs is small and is described by a
:class:`RecursiveAlgorithm`: the names of the entries of ``theta``, the compiled
kernel call, the map between the recursion's and the data's units, and the model
read-back. :func:`fit_recursive` does the rest.

Choices shared by both fitters:

* ``theta`` and ``P`` are carried from experiment to experiment and from pass to pass;
  every experiment, in every pass, starts with the internal signals at rest.
* Convergence: the passes stop when every parameter changed by less than
  ``tol * (1 + |theta_i|)`` over the last pass. Reaching ``passes`` without that (with
  ``passes > 1``) is a failure, reported as :class:`~blockid.errors.EstimationError`.
* Divergence is reported, never returned: a kernel failure names its pass, experiment,
  sample and reason; non-finite estimates and an unstable linear block are checked
  after every pass; the model finally passes :func:`~blockid.fitting.check_model`.
* A recorded history keeps at most ``history_rows`` (:mod:`blockid.config`) rows of
  ``theta`` (every ``stride``-th update), in the data's units. A failure carries the
  rows recorded up to it as ``error.history``.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid._kernels.rls import OK
from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.errors import DataError, EstimationError, ParameterError
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.checks import check_model
from blockid.fitting.result import FitResult

__all__ = [
    "given_scale_signals",
    "RecursiveAlgorithm",
    "Signals",
    "check_siso",
    "fit_recursive",
    "history_stride",
    "initial_vector",
    "int_at_least",
    "largest_lag",
    "normalised_signals",
    "one_step_metrics",
    "poles_of",
    "positive_number",
]

_CONVERGENCE_DOC = "See docs/convergence.md"


# ---------------------------------------------------------------------- validation
def int_at_least(name: str, value: Any, low: int) -> int:
    """``value`` as an int, or a :class:`ParameterError` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise ParameterError(f"{name}={value!r} must be a whole number >= {low}")
    return int(value)


def orders_at_least(minimums: dict[str, int], **values: Any) -> tuple[int, ...]:
    """``values`` as ints, in the order given, each checked against its method's one
    declaration of its minimum in ``minimums`` (e.g. key-term RLS's ``nb >= 1``)."""
    return tuple(int_at_least(name, value, minimums[name]) for name, value in values.items())


def positive_number(name: str, value: Any) -> float:
    """``value`` as a positive finite float, or a :class:`ParameterError` naming ``name``."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ParameterError(f"{name} must be a positive finite number, got {value!r}")
    return number


def check_siso(data: Dataset, method: str) -> None:
    """Raise a :class:`DataError` unless ``data`` is a Dataset with one input and output."""
    if not isinstance(data, Dataset):
        raise DataError(f"{method} needs a blockid Dataset, got {type(data).__name__}")
    if data.n_inputs != 1 or data.n_outputs != 1:
        raise DataError(
            f"{method} identifies one input and one output, but the data have "
            f"{data.n_inputs} inputs and {data.n_outputs} outputs; select one of each"
        )


def initial_vector(value: Any, n: int, names: list[str]) -> np.ndarray:
    """``theta(0)``: a number for every entry, or one value per parameter."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.full(n + 1, np.nan)  # reported below
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ParameterError(
            f"initial_parameters must be a finite number or {n} finite values "
            f"({', '.join(names)}), got {value!r}"
        )
    return arr.copy()


def largest_lag(na: int, nb: int, nk: int) -> int:
    """Samples of every experiment before the first update: the linear block's largest
    lag (MATLAB orders), at least 1."""
    return max(na, nk + nb - 1, 1)


# ---------------------------------------------------------------------- signals
@dataclass(frozen=True)
class Signals:
    """Every experiment's input and output as the recursion sees them.

    Attributes
    ----------
    records : list of (name, u, y)
        Normalised signals of every experiment, ``(signal - offset) / scale``.
    u_map, y_map : (offset, scale)
        How ``u`` and ``y`` were normalised.
    normalized : bool
        Whether they were (else offsets 0, scales 1).
    """

    records: list[tuple[str, np.ndarray, np.ndarray]]
    u_map: tuple[float, float]
    y_map: tuple[float, float]
    normalized: bool

    @property
    def y_max(self) -> float:
        """Largest ``|y|`` of the normalised outputs (for the kernels' divergence limits)."""
        return max(float(np.max(np.abs(y))) for _, _, y in self.records)


def normalised_signals(data: Dataset, normalize: bool, center: bool = False) -> Signals:
    """The single input and output of every experiment, normalised.

    With ``normalize`` the scale is the spread (standard deviation over all
    experiments), else 1; with ``center`` too the offset is the mean, else 0. The
    spread, not the RMS, so that a signal recorded around a large operating point keeps
    its variation at unit size.
    """
    u_all = np.concatenate([e.u[:, 0] for e in data.experiments])
    y_all = np.concatenate([e.y[:, 0] for e in data.experiments])
    u0 = float(np.mean(u_all)) if normalize and center else 0.0
    y0 = float(np.mean(y_all)) if normalize and center else 0.0
    su = _spread(u_all) if normalize else 1.0
    sy = _spread(y_all) if normalize else 1.0
    records = [
        (
            e.name,
            np.ascontiguousarray((e.u[:, 0] - u0) / su),
            np.ascontiguousarray((e.y[:, 0] - y0) / sy),
        )
        for e in data.experiments
    ]
    return Signals(records, (u0, su), (y0, sy), bool(normalize))


def _spread(x: np.ndarray) -> float:
    """Standard deviation, else RMS (constant signal), else 1 (all zero)."""
    return float(np.std(x)) or float(np.sqrt(np.mean(x**2))) or 1.0


# ---------------------------------------------------------------------- algorithm
class RecursiveAlgorithm(ABC):
    """What one recursive fitter adds to :func:`fit_recursive`.

    An instance describes one fit: it is built from the validated settings and the
    :class:`Signals` (its unit maps and divergence limits depend on them).

    Attributes
    ----------
    method : str
        Name in messages (``"key-term RLS"``).
    label : str
        ``FitResult.method`` (``"key-term-rls"``).
    names : list of str
        Names of the entries of ``theta``, in the recursion's order.
    n0 : int
        Samples of every experiment before its first update (the largest lag).
    a : slice
        Where ``a_1 .. a_na`` of the linear block sit in ``theta`` (poles checked after
        every pass).
    reasons : dict
        Explanation of every failure reason the kernel returns.
    """

    method: str
    label: str
    #: What to try when the model does worse than the linear baseline (None: the
    #: default advice of :func:`~blockid.fitting.check_model`).
    advice: str | None = None
    names: list[str]
    n0: int
    a: slice
    reasons: dict[int, str]

    @abstractmethod
    def run(
        self,
        theta: np.ndarray,
        P: np.ndarray,
        u: np.ndarray,
        y: np.ndarray,
        count: int,
        hist: np.ndarray,
        stride: int,
    ) -> tuple[int, int, str]:
        """One pass over one experiment, updating ``theta`` and ``P`` in place.

        ``count`` is the number of updates before this experiment in the current pass
        (0: a new pass); ``hist`` receives ``theta`` after every ``stride``-th update.
        Returns the kernel's status (``OK`` or the failing sample), its reason and a
        text added to a failure report.
        """

    @abstractmethod
    def to_data_units(self, theta: np.ndarray) -> np.ndarray:
        """``theta`` (one vector or rows) on the normalised signals, in the data's units."""

    @abstractmethod
    def from_data_units(self, theta: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_data_units` for one vector."""

    @abstractmethod
    def model(self, theta: np.ndarray, data: Dataset) -> Any:
        """The identified model from ``theta`` in the data's units; raises
        :class:`EstimationError` when ``theta`` does not describe one."""

    def model_to_check(self, model: Any) -> Any:
        """What :func:`~blockid.fitting.check_model` checks (the model itself)."""
        return model

    @abstractmethod
    def settings(self, common: dict[str, Any]) -> dict[str, Any]:
        """``FitResult.settings``: the algorithm's own, merged with the driver's
        ``common`` ones (passes, passes_run, converged, tol, initial_covariance,
        initial_parameters, normalize)."""


# ---------------------------------------------------------------------- driver
def history_stride(passes: int, n_updates: int) -> int:
    """Keep every ``stride``-th parameter vector so at most ``history_rows``
    (:mod:`blockid.config`) are kept."""
    return max(1, math.ceil(passes * n_updates / get_config()["history_rows"]))


class _Trajectory:
    """Rows of ``theta`` kept every ``stride`` updates, with their update counts."""

    def __init__(self, n: int, stride: int) -> None:
        self.n = n  # entries of theta
        self.stride = stride  # one row every `stride` updates
        self.rows: list[np.ndarray] = []  # rows of every experiment run, in order
        self.at: list[np.ndarray] = []  # update count (over all passes) of each row

    def keep(self, hist: np.ndarray, status: int, n0: int, count: int) -> None:
        """Keep the rows a kernel wrote into ``hist`` (those before a failure at sample
        ``status``); ``count`` is the number of updates before it over all passes."""
        m = hist.shape[0]
        kept = m if status == OK else min(m, max(0, (status - n0) // self.stride))
        self.rows.append(hist[:kept])
        self.at.append(count + self.stride * np.arange(1, kept + 1))

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        theta = np.vstack(self.rows) if self.rows else np.zeros((0, self.n))
        update = np.concatenate(self.at) if self.at else np.zeros(0)
        return theta, update


def _run_passes(
    algorithm: RecursiveAlgorithm,
    theta: np.ndarray,
    P: np.ndarray,
    records: list[tuple[str, np.ndarray, np.ndarray]],
    *,
    passes: int,
    tol: float,
    stride: int,
    trajectory: _Trajectory | None,
) -> tuple[int, bool | None]:
    """Repeat passes of the algorithm's kernel until ``theta`` settles; raise on failure.

    Returns the number of passes run and whether they converged (None for one pass).
    """
    n0, method = algorithm.n0, algorithm.method
    count = 0  # updates over all passes
    converged: bool | None = None
    change = np.inf
    for p in range(1, passes + 1):
        before = theta.copy()
        in_pass = 0  # updates in this pass (where a forgetting schedule stands)
        for name, u, y in records:
            m = (u.shape[0] - n0) // stride if trajectory is not None else 0
            hist = np.zeros((m, theta.size))
            status, reason, detail = algorithm.run(theta, P, u, y, in_pass, hist, stride)
            if trajectory is not None:
                trajectory.keep(hist, status, n0, count)
            if status != OK:
                raise EstimationError(
                    f"{method} diverged in pass {p}, experiment '{name}', at sample "
                    f"{status}: {algorithm.reasons[reason]}{detail}. No model is returned; "
                    f"try other orders, more exciting data or another method. "
                    f"{_CONVERGENCE_DOC}"
                )
            count += u.shape[0] - n0
            in_pass += u.shape[0] - n0
        if not np.all(np.isfinite(theta)):
            raise EstimationError(
                f"{method} diverged in pass {p}: the parameter estimates are not finite. "
                f"{_CONVERGENCE_DOC}"
            )
        rho = float(np.max(np.abs(poles_of(theta[algorithm.a])), initial=0.0))
        if not rho < 1.0:
            raise EstimationError(
                f"{method} diverged: after pass {p} the linear block is unstable (largest "
                f"pole magnitude {rho:.4g}), so its internal signals grow without bound. "
                f"No model is returned. {_CONVERGENCE_DOC}"
            )
        if p > 1:
            change = float(np.max(np.abs(theta - before) / (1.0 + np.abs(theta))))
            if change < tol:
                converged = True
                break
    else:
        if passes > 1:
            raise EstimationError(
                f"{method} did not converge in {passes} passes: the parameters still "
                f"changed by up to {change:.3g} (relative) in the last pass, tolerance "
                f"{tol:g}. Raise passes, or the internal-variable iteration has no stable "
                f"fixed point on these data. {_CONVERGENCE_DOC}"
            )
    return p, converged


def fit_recursive(
    data: Dataset,
    signals: Signals,
    algorithm: RecursiveAlgorithm,
    *,
    initial_parameters: Any,
    initial_covariance: float,
    passes: int,
    tol: float,
    record_history: bool,
) -> FitResult:
    """Run a recursive algorithm over ``signals`` in passes and return the checked model.

    The arguments are validated by the fitter (see :func:`int_at_least`,
    :func:`positive_number`). ``initial_parameters`` is a number used for every entry of
    the recursion's ``theta(0)`` or a vector in the data's units;
    ``P(0) = initial_covariance * I``.

    Raises
    ------
    EstimationError
        The kernel failed (its pass, experiment, sample and reason are named), the
        estimates became non-finite, the linear block unstable after a pass, the passes
        did not converge (``passes > 1``), or the model could not be read back or fails
        :func:`~blockid.fitting.check_model`. With ``record_history`` it carries the
        history recorded up to the failure as ``history``.
    """
    names = algorithm.names
    n = len(names)
    theta = initial_vector(initial_parameters, n, names)
    if np.ndim(initial_parameters) != 0:  # given in the data's units
        theta = algorithm.from_data_units(theta)
    P = initial_covariance * np.eye(n)
    n_updates = sum(u.shape[0] - algorithm.n0 for _, u, _ in signals.records)
    stride = history_stride(passes, n_updates)
    trajectory = _Trajectory(n, stride) if record_history else None

    def history() -> dict[str, Any]:
        rows, update = trajectory.arrays()
        return {"theta": algorithm.to_data_units(rows), "names": names, "update": update}

    try:
        n_passes, converged = _run_passes(
            algorithm,
            theta,
            P,
            signals.records,
            passes=passes,
            tol=tol,
            stride=stride,
            trajectory=trajectory,
        )
        theta = algorithm.to_data_units(theta)
        model = algorithm.model(theta, data)
        check_model(algorithm.model_to_check(model), data, algorithm.method,
                    advice=algorithm.advice)  # fmt: skip
    except EstimationError as exc:
        if trajectory is not None:
            exc.history = history()
        raise

    settings = algorithm.settings(
        {
            "passes": passes,
            "passes_run": n_passes,
            "converged": converged,
            "tol": tol,
            "initial_covariance": initial_covariance,
            "initial_parameters": np.asarray(initial_parameters, dtype=float).tolist(),
            "normalize": signals.normalized,
        }
    )
    return FitResult(
        model=model,
        method=algorithm.label,
        settings=settings,
        estimation_metrics=one_step_metrics(model, data),
        n_samples=int(data.n_samples),
        history=history() if trajectory is not None else {},
    )


# ---------------------------------------------------------------------- read-back
def poles_of(a: np.ndarray) -> np.ndarray:
    """Roots of ``z^na + a_1 z^(na-1) + .. + a_na`` (the poles of ``1/A``)."""
    return np.roots(np.concatenate(([1.0], a))) if a.size else np.zeros(0)


def one_step_metrics(model: Any, data: Dataset) -> dict[str, dict[str, float]]:
    """One-step-ahead metrics on the estimation data; ``{}`` when the model cannot predict
    one step ahead (an output polynomial not invertible over the measured range)."""
    try:
        y_hat = [model.predict(e.u, e.y) for e in data.experiments]
    except EstimationError:
        return {}
    lag = model.max_lag
    y = np.vstack([e.y[lag:] for e in data.experiments])
    return metrics_by_output(y, np.vstack([yh[lag:] for yh in y_hat]), model.outputs)


def given_scale_signals(data: Dataset, scales: Any) -> Signals:
    """The signals divided by given scales ``(s_u, s_y)`` instead of measured spreads
    (no offsets): what a recursion that cannot see the whole record first, such as
    :mod:`blockid.fitting.online`, runs on."""
    try:
        su, sy = scales
    except (TypeError, ValueError):
        raise ParameterError(
            f"scales must be a pair (input scale, output scale), got {scales!r}"
        ) from None
    su, sy = positive_number("input scale", su), positive_number("output scale", sy)
    raw = normalised_signals(data, False)
    records = [(name, u / su, y / sy) for name, u, y in raw.records]
    return Signals(records, (0.0, su), (0.0, sy), True)
