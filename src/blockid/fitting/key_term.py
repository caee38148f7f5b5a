"""Paper B's key-term RLS with internal-variable estimation (B4, B5), and its pass driver.

Key-term separation makes the Hammerstein-Wiener model linear in its parameters once
the unmeasured internal signals ``w`` and ``x`` are known (B4):

.. math::

    y(k) = \\sum_{l=0}^{r_1} f_l u^l(k-n_k) + \\sum_{l=0}^{r_1} p_l u^l(k-n_k) h(u(k-n_k))
           + \\sum_{i\\ge 1} b_i w(k-n_k-i) - \\sum_{j=1}^{n_a} a_j x(k-j)
           + \\sum_{m=2}^{r_2} q_m x^m(k)

with ``b_0 = q_1 = 1``. The recursion (B5) replaces ``w`` and ``x`` by estimates
computed sample by sample from the newest parameters and takes one RLS step with a
forgetting factor; passes over the data repeat until the parameters stop changing.
The compiled pass is :func:`blockid._kernels.key_term.key_term_run`.

The same algorithm with a block removed gives paper B's comparison models:
``"hammerstein"`` (no ``q``; ``x = y`` is measured), ``"wiener"`` (``w = u``, ``b_0``
free) and ``"arx"`` (both removed: plain RLS on the ARX regressor).

Choices (SPEC leaves them open):

* The forgetting schedule restarts with every pass (paper B: lambda = 0.98 over the
  first 200 samples of the data, 1 afterwards); ``theta`` and ``P`` are carried from
  pass to pass. The restart discounts the previous pass, whose regressors were built
  from older internal-signal estimates, by 0.98^200 ~ 0.02, so a pass re-estimates
  from mostly fresh internal signals and the passes converge to a fixed point of the
  iteration. Counting the schedule once over all passes instead leaves lambda = 1 and
  a shrinking ``P`` after the first pass: later passes barely move the estimate and,
  in our experiments, never reached the tolerance (docs/convergence.md).
* Every experiment, in every pass, starts with the internal signals at rest (0 before
  its first sample); ``theta`` and ``P`` are carried from one experiment to the next.
* Convergence: the passes stop when every parameter changed by less than
  ``tol * (1 + |theta_i|)`` over the last pass. Reaching ``passes`` without that (with
  ``passes > 1``) is a failure, reported as :class:`~blockid.errors.EstimationError`.
* The recursion runs on ``u / std(u)``, ``y / std(y)`` (``normalize=True``) and the
  parameters are mapped back exactly; on raw signals its behaviour depends on the
  units (``P(0) = 1e6 I`` meets ``x^3`` of large signals).
* Divergence is detected while running: a non-finite RLS step, an internal signal
  ``|x_hat|`` beyond ``1e6 (1 + max|y|)``, and, after every pass, an unstable linear
  block. The returned model then passes :func:`~blockid.fitting.check_model`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from blockid._kernels import key_term as _k
from blockid._kernels.rls import OK
from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.data.dataset import Dataset
from blockid.errors import DataError, EstimationError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.evaluation.metrics import metrics_by_output
from blockid.fitting.checks import check_model
from blockid.fitting.result import FitResult
from blockid.models.arx import ARX
from blockid.models.block import BlockModel, Hammerstein, HammersteinWiener, Wiener

__all__ = ["KEY_TERM_STRUCTURES", "fit_key_term_rls"]

#: Structures :func:`fit_key_term_rls` identifies: (input block?, output block?).
KEY_TERM_STRUCTURES = {
    "hammerstein-wiener": (True, True),
    "hammerstein": (True, False),
    "wiener": (False, True),
    "arx": (False, False),
}

#: Largest number of parameter vectors kept in a recorded history (decimated beyond).
HISTORY_ROWS = 20_000

_CONVERGENCE_DOC = "See docs/convergence.md"


# ---------------------------------------------------------------------- validation
def int_at_least(name: str, value: Any, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise ParameterError(f"{name}={value!r} must be a whole number >= {low}")
    return int(value)


def positive_number(name: str, value: Any) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a positive number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ParameterError(f"{name} must be a positive finite number, got {value!r}")
    return number


def check_siso(data: Dataset, method: str) -> None:
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


# ---------------------------------------------------------------------- pass driver
def history_stride(passes: int, n_updates: int) -> int:
    """Keep every ``stride``-th parameter vector so at most ``HISTORY_ROWS`` are kept."""
    return max(1, math.ceil(passes * n_updates / HISTORY_ROWS))


def signals(
    data: Dataset, normalize: bool, center: bool = False
) -> tuple[list[tuple[str, np.ndarray, np.ndarray]], tuple[float, float], tuple[float, float]]:
    """``(name, u, y)`` of every experiment, normalised, and the ``(offset, scale)`` of
    ``u`` and of ``y``: ``(signal - offset) / scale``.

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
    out = [
        (
            e.name,
            np.ascontiguousarray((e.u[:, 0] - u0) / su),
            np.ascontiguousarray((e.y[:, 0] - y0) / sy),
        )
        for e in data.experiments
    ]
    return out, (u0, su), (y0, sy)


def _spread(x: np.ndarray) -> float:
    """Standard deviation, else RMS (constant signal), else 1 (all zero)."""
    return float(np.std(x)) or float(np.sqrt(np.mean(x**2))) or 1.0


def start_vector(value: Any, factors: np.ndarray, names: list[str]) -> np.ndarray:
    """``theta(0)`` on the normalised signals: a number as it is (the papers' small equal
    values), a vector given in the data's units divided by the unscaling ``factors``."""
    theta = initial_vector(value, factors.size, names)
    return theta if np.ndim(value) == 0 else theta / factors


def run_passes(
    run: Callable[[np.ndarray, np.ndarray, int, np.ndarray, int], tuple[int, int, str]],
    theta: np.ndarray,
    records: list[tuple[str, np.ndarray, np.ndarray]],
    *,
    n0: int,
    passes: int,
    tol: float,
    record: bool,
    method: str,
    reasons: dict[int, str],
    poles: Callable[[np.ndarray], np.ndarray],
) -> tuple[int, bool | None, np.ndarray | None, np.ndarray | None]:
    """Repeat passes of a recursive kernel until ``theta`` settles; raise on failure.

    ``run(u, y, count, hist, stride) -> (status, reason, detail)`` processes one
    experiment once, updating ``theta`` in place (``detail``: text added to a failure
    report); ``count`` is the number of updates before it in
    the current pass (where a forgetting schedule stands). ``records`` holds ``(name,
    u, y)`` per experiment. ``poles(theta)`` gives the linear block's poles, checked
    after every pass.

    Returns the number of passes run, whether they converged (None for one pass), and
    the recorded history (rows of ``theta`` and their update counts) or None.
    """
    n_updates = sum(u.size - n0 for _, u, _ in records)
    stride = history_stride(passes, n_updates)
    rows: list[np.ndarray] = []
    at: list[np.ndarray] = []
    count = 0
    converged: bool | None = None
    change = np.inf

    def failure(message: str) -> EstimationError:
        exc = EstimationError(message)
        if record:  # in the recursion's units; the caller converts (see recorded_history)
            exc.history = {
                "theta": np.vstack(rows) if rows else np.zeros((0, theta.size)),
                "update": np.concatenate(at) if at else np.zeros(0),
            }
        return exc

    for p in range(1, passes + 1):
        before = theta.copy()
        in_pass = 0
        for name, u, y in records:
            m = (u.size - n0) // stride if record else 0
            hist = np.zeros((m, theta.size))
            status, reason, detail = run(u, y, in_pass, hist, stride)
            if record:
                # Rows the kernel wrote before a failure at sample `status`.
                kept = m if status == OK else min(m, max(0, (status - n0) // stride))
                rows.append(hist[:kept])
                at.append(count + stride * np.arange(1, kept + 1))
            if status != OK:
                raise failure(
                    f"{method} diverged in pass {p}, experiment '{name}', at sample "
                    f"{status}: {reasons[reason]}{detail}. No model is returned; try other "
                    f"orders, more exciting data or another method. {_CONVERGENCE_DOC}"
                )
            count += u.size - n0
            in_pass += u.size - n0
        if not np.all(np.isfinite(theta)):
            raise failure(
                f"{method} diverged in pass {p}: the parameter estimates are not finite. "
                f"{_CONVERGENCE_DOC}"
            )
        rho = float(np.max(np.abs(poles(theta)), initial=0.0))
        if not rho < 1.0:
            raise failure(
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
            raise failure(
                f"{method} did not converge in {passes} passes: the parameters still "
                f"changed by up to {change:.3g} (relative) in the last pass, tolerance "
                f"{tol:g}. Raise passes, or the internal-variable iteration has no stable "
                f"fixed point on these data. {_CONVERGENCE_DOC}"
            )
    hist_theta = np.vstack(rows) if record else None
    hist_at = np.concatenate(at) if record else None
    return p, converged, hist_theta, hist_at


@contextlib.contextmanager
def history_on_failure(
    record: bool, names: list[str], to_data_units: Callable[[np.ndarray], np.ndarray]
) -> Iterator[dict[str, Any]]:
    """Give an :class:`EstimationError` raised inside the recorded history, in data units.

    :func:`run_passes` attaches the rows recorded up to its own failures; for a failure
    after it (a check of the result), put its history in the yielded dict under
    ``"raw"`` (``{"theta", "update"}`` in the recursion's units).
    """
    state: dict[str, Any] = {}
    try:
        yield state
    except EstimationError as exc:
        raw = exc.history if exc.history is not None else state.get("raw")
        if record and raw is not None and "names" not in raw:
            exc.history = {
                "theta": to_data_units(raw["theta"]),
                "names": names,
                "update": raw["update"],
            }
        raise


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


# ---------------------------------------------------------------------- key-term RLS
def _layout(structure: str, na: int, nb: int, r1: int, r2: int) -> list[str]:
    """Names of the entries of theta in the order of (B4)."""
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    names = []
    if has_in:
        names += [f"f_{l}" for l in range(r1 + 1)] + [f"p_{l}" for l in range(r1 + 1)]
    names += [f"b_{i}" for i in range(1 if has_in else 0, nb)]
    names += [f"a_{j}" for j in range(1, na + 1)]
    if has_out:
        names += [f"q_{m}" for m in range(2, r2 + 1)]
    return names


def _unscale(structure: str, na: int, nb: int, r1: int, r2: int, su: float, sy: float):
    """Factors taking theta on ``u/su, y/sy`` back to the data's units (element-wise).

    With ``w, x`` scaled like ``y``: ``f_l, p_l`` scale by ``sy/su^l``, ``b`` by
    ``sy/su`` without an input block (else 1), ``a`` by 1 and ``q_m`` by ``sy^(1-m)``.
    """
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    parts = []
    if has_in:
        fp = sy / su ** np.arange(r1 + 1)
        parts += [fp, fp, np.ones(nb - 1)]
    else:
        parts.append(np.full(nb, sy / su))
    parts.append(np.ones(na))
    if has_out:
        parts.append(sy ** (1.0 - np.arange(2, r2 + 1)))
    return np.concatenate(parts)


def _model(
    structure: str, theta: np.ndarray, data: Dataset, na: int, nb: int, nk: int, r1: int
) -> Any:
    """The identified model from theta (B4 order)."""
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    pos = 0
    kwargs: dict[str, Any] = dict(na=na, nb=nb, nk=nk, sampling_time=data.sampling_time)
    if has_in:
        f, p = theta[: r1 + 1], theta[r1 + 1 : 2 * r1 + 2]
        kwargs["input_block"] = TwoSegmentPolynomial(f, p)
        pos = 2 * r1 + 2
        b = np.concatenate(([1.0], theta[pos : pos + nb - 1]))
        pos += nb - 1
    else:
        b = theta[pos : pos + nb]
        pos += nb
    a = theta[pos : pos + na]
    pos += na
    kwargs.update(a=a, b=b)
    if has_out:
        kwargs["output_block"] = Polynomial(np.concatenate(([1.0], theta[pos:])), constant=False)
    u_name, y_name = data.inputs[0], data.outputs[0]
    if structure == "arx":
        return ARX(
            [u_name],
            [y_name],
            na,
            nb,
            nk,
            a={y_name: {y_name: a}},
            b={y_name: {u_name: b}},
            sampling_time=data.sampling_time,
        )
    cls = {"hammerstein-wiener": HammersteinWiener, "hammerstein": Hammerstein}.get(
        structure, Wiener
    )
    return cls(u_name, y_name, **kwargs)


def fit_key_term_rls(
    data: Dataset,
    structure: str,
    *,
    na: int = 3,
    nb: int = 3,
    nk: int = 8,
    r1: int = 3,
    r2: int = 3,
    forgetting: float | str | ForgettingSchedule = "0.98:200,1",
    passes: int = 20,
    tol: float = 1e-6,
    initial_covariance: float = 1e6,
    initial_parameters: Any = 0.01,
    normalize: bool = True,
    record_history: bool = False,
) -> FitResult:
    """Identify a block-oriented model by paper B's key-term RLS (B4, B5).

    Parameters
    ----------
    data : Dataset
        One input, one output; several experiments are processed one after another.
    structure : {"hammerstein-wiener", "hammerstein", "wiener", "arx"}
        Which blocks the model has (paper B's H-W model and its comparison models).
    na, nb, nk : int
        Linear block orders, MATLAB convention (``nb`` counts ``b_0``, fixed to 1 when
        there is an input block). Paper B: ``na = 3, nb = 3, nk = 8``.
    r1, r2 : int
        Degrees of the two-segment input polynomial (B1, ``>= 1``) and of the output
        polynomial (B3, ``>= 2``). Ignored for a structure without that block.
    forgetting : float or str
        Forgetting factor or schedule (paper B: ``"0.98:200,1"``).
    passes : int
        Maximum number of passes over the data.
    tol : float
        Convergence tolerance on the relative parameter change over one pass.
    initial_covariance : float
        ``P(0) = initial_covariance * I`` (paper B: 1e6), for the normalised signals
        when ``normalize``.
    initial_parameters : float or sequence
        ``theta(0)``: a number is used for every entry of the recursion's vector (on the
        normalised signals when ``normalize``; paper: small equal values); a sequence gives
        ``theta(0)`` in the data's units, in the order of ``history["names"]``.
    normalize : bool
        Run the recursion on ``u / std(u)`` and ``y / std(y)`` and map the parameters
        back exactly (default). Only divided, never shifted: the polynomial blocks are
        not invariant to offsets (the two segments meet at ``u = 0``, the output
        polynomial has no constant). The papers work on raw signals
        (``normalize=False``); then
        convergence depends on the units: the same plant with ``u`` in other units
        fails in the first samples (too large) or stalls (too small).
    record_history : bool
        Keep the parameter trajectory (decimated to at most ``HISTORY_ROWS`` rows, in
        the data's units) in ``result.history``: ``"theta"`` (rows), ``"names"``,
        ``"update"`` (update count of every row, counted over all passes).

    Returns
    -------
    FitResult
        ``model`` is a :class:`~blockid.models.HammersteinWiener`,
        :class:`~blockid.models.Hammerstein`, :class:`~blockid.models.Wiener` or
        :class:`~blockid.models.ARX`.

    Raises
    ------
    EstimationError
        The recursion diverged (non-finite step, exploding internal signal, unstable
        linear block after a pass), did not converge in ``passes``, or the model fails
        :func:`~blockid.fitting.check_model`.

    Examples
    --------
    A Hammerstein plant (two-segment input block, paper B's orders) driven by white
    noise:

    >>> import numpy as np
    >>> from blockid.blocks import TwoSegmentPolynomial
    >>> from blockid.data import Dataset
    >>> from blockid.models import Hammerstein
    >>> n1 = TwoSegmentPolynomial.from_segments(positive=[0, 0.3, 0.1], negative=[0, 0.15])
    >>> plant = Hammerstein("u", "y", input_block=n1, na=3, nb=3, nk=8,
    ...                     a=[-0.9, -0.01, 0.105], b=[1.0, 0.5, 0.2])
    >>> u = np.random.default_rng(0).uniform(-1.0, 1.0, 3000)
    >>> data = Dataset.from_arrays(u, plant.simulate(u), inputs=["u"], outputs=["y"])
    >>> fit = fit_key_term_rls(data, "hammerstein", r1=2)
    >>> fit.settings["converged"], np.round(fit.model.a, 4).tolist()
    (True, [-0.9, -0.01, 0.105])
    """
    method = "key-term RLS"
    if structure not in KEY_TERM_STRUCTURES:
        raise ParameterError(
            f"unknown structure {structure!r} for key-term RLS; choose one of "
            f"{', '.join(KEY_TERM_STRUCTURES)}"
        )
    check_siso(data, method)
    has_in, has_out = KEY_TERM_STRUCTURES[structure]
    na = int_at_least("na", na, 0)
    nb = int_at_least("nb", nb, 1)
    nk = int_at_least("nk", nk, 0)
    r1 = int_at_least("r1", r1, 1) if has_in else 0
    r2 = int_at_least("r2", r2, 2) if has_out else 1
    passes = int_at_least("passes", passes, 1)
    tol = positive_number("tol", tol)
    mu = positive_number("initial_covariance", initial_covariance)
    schedule = ForgettingSchedule.parse(forgetting)
    names = _layout(structure, na, nb, r1, r2)
    n = len(names)
    n0 = max(na, nk + nb - 1, 1)
    data.check_orders(n0, n, what=f"key-term RLS {structure} na={na}, nb={nb}, nk={nk}")
    records, (_, su), (_, sy) = signals(data, normalize)
    factors = _unscale(structure, na, nb, r1, r2, su, sy)
    theta = start_vector(initial_parameters, factors, names)

    P = mu * np.eye(n)
    y_max = max(float(np.max(np.abs(y))) for _, _, y in records)
    limits = np.array([mu * n, 1e6 * (1.0 + y_max)])
    ia = (2 * r1 + 2 if has_in else 0) + nb - (1 if has_in else 0)
    orders = np.array([r1, nb, na, r2, nk, has_in, has_out, n0, 1], dtype=np.int64)

    def run(u: np.ndarray, y: np.ndarray, count: int, hist: np.ndarray, stride: int):
        N = u.size
        lam = np.ones(N)
        lam[n0:] = schedule.factors(count, N - n0)
        orders[8] = stride
        w, x = np.empty(N), np.empty(N)
        status, reason = _k.key_term_run(theta, P, u, y, lam, orders, limits, w, x, hist)
        detail = ""
        if status != OK and has_out:
            x_max = float(np.max(np.abs(x[:status]), initial=0.0)) * sy
            detail = f" (largest |x_hat| so far {x_max:.3g}, largest |y| {y_max * sy:.3g})"
        return status, reason, detail

    reasons = {
        _k.REASON_STEP: "the RLS update became non-finite or lost positive definiteness",
        _k.REASON_EXPLODED: "the estimated internal signal x exceeded 1e6 (1 + max|y|): "
        "the estimated linear block drives it unstable",
    }
    with history_on_failure(record_history, names, lambda rows: rows * factors) as state:
        n_passes, converged, hist_theta, hist_at = run_passes(
            run,
            theta,
            records,
            n0=n0,
            passes=passes,
            tol=tol,
            record=record_history,
            method=method,
            reasons=reasons,
            poles=lambda th: poles_of(th[ia : ia + na]),
        )
        state["raw"] = {"theta": hist_theta, "update": hist_at}
        theta = theta * factors
        model = _model(structure, theta, data, na, nb, nk, r1)
        checked = model if structure != "arx" else _block_twin(model, na, nb, nk)
        check_model(checked, data, method)

    settings: dict[str, Any] = {
        "structure": structure,
        "na": na,
        "nb": nb,
        "nk": nk,
        "forgetting": str(schedule),
        "passes": passes,
        "passes_run": n_passes,
        "converged": converged,
        "tol": tol,
        "initial_covariance": mu,
        "initial_parameters": np.asarray(initial_parameters, dtype=float).tolist(),
        "normalize": bool(normalize),
    }
    if has_in:
        settings["r1"] = r1
    if has_out:
        settings["r2"] = r2
    history: dict[str, Any] = {}
    if record_history:
        history = {"theta": hist_theta * factors, "names": names, "update": hist_at}
    return FitResult(
        model=model,
        method="key-term-rls",
        settings=settings,
        estimation_metrics=one_step_metrics(model, data),
        n_samples=int(data.n_samples),
        history=history,
    )


def _block_twin(model: ARX, na: int, nb: int, nk: int) -> BlockModel:
    """The same linear model as a block model without blocks, for :func:`check_model`."""
    y_name, u_name = model.outputs[0], model.inputs[0]
    return BlockModel(
        u_name,
        y_name,
        na=na,
        nb=nb,
        nk=nk,
        a=model.a[y_name][y_name],
        b=model.b[y_name][u_name],
        sampling_time=model.sampling_time,
    )
