"""Online learning: the recursive methods fed a record chunk by chunk or sample by sample.

:func:`online_estimator` builds the backend of
:meth:`blockid.fitting.estimator.ModelEstimator.partial_fit` and ``update`` for every
recursive method of the registry: ARX ``rls``, ``aw-rls`` and ``hierarchical-rls``
(A2, A8, A10), paper B's ``key-term-rls`` (B4, B5) for Hammerstein, Wiener and
Hammerstein-Wiener models (of several inputs channel by channel,
:mod:`blockid.fitting.key_term_channels`, also as ``block-state-space``), and paper A's
``aw-rls`` for the backlash model (A6–A8).

Equivalence contract. The samples of one record fed through
:meth:`OnlineEstimator.partial_fit` in any chunks, or one at a time through
:meth:`OnlineEstimator.update`, end with the estimate of the one-pass offline fit of
that record with the same options and the matching scaling (below): bit for bit, since
the same compiled kernels run the same operations. The kernels continue a pass from a
carried state (``start`` entry of their ``orders``, see
:mod:`blockid._kernels.key_term`): what is carried from chunk to chunk is ``theta``,
``P``, the number of samples seen (where a forgetting schedule stands and when the
first update comes) and the last ``max_lag`` samples of ``u``, ``y`` and of the
internal estimates (``w_hat, x_hat``; ``x_hat, f1_hat, f2_hat`` for the backlash), so
the memory does not grow with the record.

Scaling (a choice). The offline paper fitters divide the signals by their spread over
the whole record (``normalize=True``) and :func:`~blockid.fitting.arx.fit_arx` divides
the regressor columns by their RMS over the record; neither is known before the record
has been seen. Online learning therefore runs on the signals as they are, unless the
user gives the scales, ``input_scale`` and ``output_scale`` (options only online
learning takes: the recursion then runs on ``u / input_scale`` and ``y /
output_scale``, and the parameters are mapped back exactly, as offline). So:

=========================  ================================================================
online options             equal to the offline one-pass fit
=========================  ================================================================
(no scales)                ``fit_key_term_rls(.., normalize=False)`` (several inputs:
                           ``fit_key_term_channels(.., normalize=False)``),
                           ``fit_backlash_aw_rls(.., normalize=False)``,
                           ``fit_arx(.., scaling="none")``
``input_scale=su,``        ``fit_key_term_rls(.., scales=(su, sy))`` (several inputs:
                           ``fit_key_term_channels(.., scales=(su, sy))``),
``output_scale=sy``        ``fit_backlash_aw_rls(.., scales=(su, sy))``,
                           ``fit_arx(.., scaling=(su, sy))``
=========================  ================================================================

all with ``passes=1``. ``initial_covariance`` is relative to the signals so scaled (or
raw): on raw signals far from order one, give the scales (their expected spread) or a
``P(0)`` that fits the units. ``normalize=True`` without scales is refused: there is
no spread to divide by. The papers' recursions run on raw signals in any case.

Other options. ``initial`` (only online) is a model of the structure whose parameters
set ``theta(0)`` (its orders are used where none are given; its offsets must be 0);
``initial_parameters`` sets ``theta(0)`` as offline. Whole-record settings cannot
apply to a stream: ``passes`` must be 1, ``center``, ``refine`` and
``record_history`` are refused, and ``tol``, ``convergence_check``,
``max_mse_ratio``, ``allow_unstable`` (checks of a finished offline fit) are accepted
and not used. Online learning does not centre: a Wiener model, centred by default
offline, is learned around 0.

Divergence. A failing step (non-finite, ``P`` no longer positive definite), an
exploding internal estimate (``|x_hat|`` beyond ``1e6 (1 + max|y|)``, ``max|y|`` over
the samples seen so far) or a zero backlash slope raises
:class:`~blockid.errors.EstimationError` naming the sample (counted from the first
sample fed, also in ``error.sample``); the backend is left as it was before the call,
so a stream can report it and go on or stop.

Not learning from a sample (for a caller that judges samples: the outlier guard of
:mod:`blockid.workflows.stream`). ``update(u, y, learn=False)`` takes a sample into the
learner's memory (the window its regressors reach back into, and the internal
estimates) and returns its prediction, leaving ``theta`` and ``P`` as they were: the
samples after it keep their true lags. :meth:`OnlineEstimator.revert` takes back the
last update's change of the estimate, the sample staying in the memory (a sample judged
by its prediction error, which exists only once the update ran); :meth:`~OnlineEstimator.snapshot`
and :meth:`~OnlineEstimator.rewind` save and put back the estimate alone (``theta``,
``P``, where a forgetting schedule stands), the memory staying current. For ARX the
held sample does not touch the recursion at all; the papers' methods run the step and
put ``theta`` and ``P`` back, so their internal estimates of that sample are the
updated estimate's (their window still moves on).
"""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid._kernels import backlash_awrls as _kb
from blockid._kernels import key_term as _kk
from blockid._kernels import key_term_channels as _kc
from blockid._kernels import rls as _kr
from blockid.errors import DataError, EstimationError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.arx import fit_arx, make_estimator, regressor_scale, signal_scales
from blockid.fitting.backlash import BacklashAWRLS, fit_backlash_aw_rls
from blockid.fitting.block_arx import (
    arx_core_model,
    fit_block_arx,
    input_basis,
    regression_orders,
    scalar_orders,
)
from blockid.fitting.dispatch import resolve_options
from blockid.fitting.key_term import KEY_TERM_STRUCTURES, KeyTermRLS, fit_key_term_rls
from blockid.fitting.key_term_channels import fit_key_term_block
from blockid.fitting.recursive import (
    Signals,
    initial_vector,
    int_at_least,
    largest_lag,
    positive_number,
)
from blockid.fitting.registry import checked
from blockid.models.arx import ARX

__all__ = ["model_parameters", "ONLINE_OPTIONS", "OnlineEstimator", "online_estimator"]

#: Options only online learning takes (not in the registry, not used by offline fits).
ONLINE_OPTIONS = ("initial", "input_scale", "output_scale")

#: Names of the ARX recursions in messages.
_ARX_NAMES = {"rls": "RLS", "aw-rls": "AW-RLS", "hierarchical-rls": "H-RLS"}

#: Options of a finished offline fit that a stream accepts and does not use.
_NOT_USED = ("tol", "convergence_check", "max_mse_ratio", "allow_unstable")


# ---------------------------------------------------------------------- entry point
def online_estimator(
    structure: str,
    method: str | None,
    options: dict[str, Any],
    inputs: Any,
    outputs: Any,
) -> OnlineEstimator:
    """The online learner of ``structure`` fitted by the recursive ``method``.

    Parameters
    ----------
    structure, method : str
        As in :func:`~blockid.fitting.fit_model`; the method must be recursive.
    options : dict
        The method's options (registry, values may be text), plus ``initial``,
        ``input_scale`` and ``output_scale`` (module docstring).
    inputs, outputs : sequence of str
        Signal names of the model.

    Examples
    --------
    >>> import numpy as np
    >>> from blockid.models import ARX
    >>> plant = ARX(["u"], ["y"], na=1, nb=1, nk=1,
    ...             a={"y": {"y": [-0.5]}}, b={"y": {"u": [2.0]}})
    >>> u = np.random.default_rng(0).standard_normal((300, 1))
    >>> online = online_estimator("arx", "rls", {}, ["u"], ["y"])
    >>> online.partial_fit(u, plant.simulate(u)).n_samples
    300
    >>> {k: np.round(v, 6).tolist() for k, v in online.parameters()["y"]["a"].items()}
    {'y': [-0.5]}
    """
    options = dict(options)
    extra = {k: options.pop(k) for k in ONLINE_OPTIONS if options.get(k) is not None}
    decl, method, opts = resolve_options(structure, method, options)
    if not decl.method(method).recursive:
        raise ParameterError(
            f"method={method!r} of {structure} is not recursive: it cannot learn online. Use "
            f"one of {', '.join(m.name for m in decl.methods if m.recursive)}"
        )
    for key in _NOT_USED:
        opts.pop(key, None)
    _refuse_whole_record(opts)
    names = (tuple(inputs), tuple(outputs))
    initial = extra.get("initial")
    if initial is not None:
        if not isinstance(initial, decl.model_class()):
            raise ParameterError(
                f"initial must be a {decl.model_class().__name__} model (structure "
                f"{structure}), got {type(initial).__name__}"
            )
        if np.any(np.asarray(initial.input_offset) != 0) or np.any(
            np.asarray(initial.output_offset) != 0
        ):
            raise ParameterError(
                "initial has non-zero offsets; online learning does not centre the signals, "
                "so it starts only from a model without offsets"
            )
        if "initial_parameters" in opts:
            raise ParameterError("give initial (a model) or initial_parameters, not both")
        _check_orders_against(initial, opts)
    scales = _scales(extra, opts)
    # the backend of the offline fitter the registry names for this method
    backend = {
        fit_arx: _OnlineARX,
        fit_key_term_rls: _OnlineKeyTerm,
        fit_backlash_aw_rls: _OnlineBacklash,
        fit_block_arx: _OnlineBlockARX,
        fit_key_term_block: _OnlineKeyTermChannels,
    }[decl.method(method).function()]
    if backend is _OnlineKeyTerm and len(names[0]) > 1:  # several inputs: channel by channel
        backend = _OnlineKeyTermChannels
    return backend(structure, method, opts, names, scales, initial)


def model_parameters(model: Any) -> dict[str, Any]:
    """A model's numbers as its file holds them: the ``parameters`` entry of a chain's
    file; a state-space model's file, whose matrices and blocks are at the top, less
    its signal names and structure."""
    doc = model.to_dict()
    if "parameters" in doc:
        return doc["parameters"]
    return {k: v for k, v in doc.items() if k not in ("structure", "inputs", "outputs",
                                                      "sampling_time")}  # fmt: skip


def _check_orders_against(initial: Any, opts: dict[str, Any]) -> None:
    """Orders given beside a starting model must be its own: the model's parameters are
    the start, laid out by its orders (other orders took them silently, or failed deep
    in NumPy)."""
    blocks = {
        "r1": getattr(getattr(initial, "input_block", None), "order", None),
        "r2": getattr(getattr(initial, "output_block", None), "degree", None),
    }
    for key in ("na", "nb", "nk", "r1", "r2"):
        value = blocks[key] if key in blocks else getattr(initial, key, None)
        if key not in opts or value is None:
            continue
        own = np.asarray(value)
        given = np.asarray(opts[key])
        if given.shape != own.shape and given.size == 1:
            given = np.broadcast_to(given.reshape(-1)[0], own.shape)
        if given.shape != own.shape or not np.array_equal(given, own):
            raise ParameterError(
                f"{key}={opts[key]!r} differs from the starting model's {key} "
                f"({own.tolist()}); its parameters are the start, so leave {key} out or "
                "start from a model of those orders",
                parameter=key,
            )


def _refuse_whole_record(opts: dict[str, Any]) -> None:
    passes = opts.pop("passes", 1)
    if passes != 1:
        raise ParameterError(
            f"passes={passes}: online learning makes one pass over the samples as they come; "
            "use passes=1 (or fit for several passes over a finished record)",
            parameter="passes",
        )
    for key in ("center", "refine", "record_history"):
        if opts.pop(key, False):
            what = {
                "center": "the means of the whole record",
                "refine": "a refinement over the whole record",
                "record_history": "a recorded trajectory (read parameters() as you go)",
            }[key]
            raise ParameterError(
                f"{key}=True needs {what}, which online learning does not have; leave it off",
                parameter=key,
            )


def _scales(extra: dict[str, Any], opts: dict[str, Any]) -> Any:
    """``None`` (raw signals) or the given (input, output) scales (checked by the
    backend)."""
    normalize = opts.pop("normalize", None)
    given = [extra.get("input_scale"), extra.get("output_scale")]
    if given == [None, None]:
        if normalize:
            raise ParameterError(
                "normalize=True divides by the spread of the whole record, which online "
                "learning cannot know in advance: give input_scale and output_scale (the "
                "expected spreads), or normalize=False",
                parameter="normalize",
            )
        return None
    if None in given:
        raise ParameterError("give both input_scale and output_scale, or neither")
    return tuple(given)


def _paper_scales(scales: Any) -> Any:
    if scales is None:
        return None
    return (
        positive_number("input_scale", scales[0]),
        positive_number("output_scale", scales[1]),
    )


def _defaults(function: Any, opts: dict[str, Any], keys: tuple[str, ...]) -> dict[str, Any]:
    """``opts`` completed with the offline fitter's defaults (one source of truth)."""
    params = inspect.signature(function).parameters
    return {k: opts[k] if k in opts else params[k].default for k in keys}


def _schedule_factor(schedule: ForgettingSchedule, count: int) -> float:
    """``schedule.factors(count, 1)[0]`` without an array (the per-sample path)."""
    edge = 0
    for value, duration in zip(schedule.values[:-1], schedule.durations, strict=True):
        edge += duration
        if count < edge:
            return value
    return schedule.values[-1]


@dataclass(frozen=True)
class _Names:
    """What a model read-back needs of a Dataset."""

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    sampling_time: float | None = None


# ---------------------------------------------------------------------- interface
class OnlineEstimator(ABC):
    """A recursive method learning from a stream (module docstring).

    Attributes
    ----------
    n_samples : int
        Samples taken in so far: learned from, or held (``update(.., learn=False)``).
    """

    #: Attributes that hold the learner's state between samples (:meth:`state`).
    _state: tuple[str, ...] = ("n_samples",)
    #: Those of them that are the estimate (:meth:`snapshot`); the rest is the memory.
    _estimate: tuple[str, ...] = ("theta", "P")

    def __init__(self, names: tuple[tuple[str, ...], tuple[str, ...]]) -> None:
        self.names = _Names(*names)  # signal names of the model
        self.n_samples = 0  # samples taken in so far (learned from or held)
        self._nu, self._ny = len(self.names.inputs), len(self.names.outputs)

    def state(self) -> dict[str, Any]:
        """Everything the learner carries from one sample to the next, as JSON-ready
        values (floats exact: JSON writes them by ``repr``). A learner built with the
        same options and given this by :meth:`restore` continues exactly as this one
        would: ``blockid stream --checkpoint`` and its resumption."""
        return {name: _encode(getattr(self, name)) for name in self._state}

    def restore(self, state: dict[str, Any]) -> OnlineEstimator:
        """Take the state of :meth:`state` (of a learner built with the same options);
        arrays are copied into place, so views of them stay valid."""
        missing = [name for name in self._state if name not in state]
        if missing:
            raise ParameterError(
                f"the saved learner state lacks {', '.join(missing)}: it was not written by "
                "this structure and method (or by another version of blockid)"
            )
        for name in self._state:
            _decode_into(self, name, state[name])
        return self

    def partial_fit(self, u: Any, y: Any) -> OnlineEstimator:
        """Learn from the next chunk, ``u`` of shape (N, nu) and ``y`` (N, ny); returns
        ``self``. The one-step predictions made before every sample's update are kept
        in ``predictions_`` (NaN before the first update)."""
        u, y = self._check(u, y)
        self.predictions_ = self._learn(u, y) if u.shape[0] else np.zeros_like(y)
        return self

    def update(self, u: Any, y: Any, learn: bool = True) -> np.ndarray:
        """Learn from one sample; returns the one-step prediction of ``y`` made with the
        estimate before the update, shape (ny,) (NaN before the first update: the
        first ``max_lag`` samples only fill the regressor).

        The prediction is the recursion's a-priori one, ``phi_hat(k)^T theta(k-1)``
        (B5, A2, A8) in the data's units: for ARX the model's one-step prediction; for
        the block-oriented models it uses the internal estimates ``x_hat, w_hat`` the
        recursion carries.

        ``learn=False`` takes the sample into the memory only: the estimate stays as it
        was (module docstring), and the prediction is made all the same.
        """
        if learn:
            return self._step(*self._sample(u, y))
        return self._hold(*self._sample(u, y))

    @property
    def max_lag(self) -> int:
        """Samples of history the recursion reaches back to: a sample is in the
        regressors of the ``max_lag`` samples after it (and of its own)."""
        return int(self.L)

    @property
    def n_parameters(self) -> int:
        """Coefficients of one recursion (of the largest, for ARX of several outputs)."""
        return int(self.theta.size)

    def revert(self) -> None:
        """Take back the estimate change (``theta``, ``P``, the schedule's count) of
        the last sample learned by :meth:`update`; the sample stays in the memory.

        >>> online = online_estimator("arx", "rls", {"na": 1, "nb": 1}, ["u"], ["y"])
        >>> for u, y in [(1.0, 0.0), (0.5, 2.0), (-1.0, 1.5)]:
        ...     _ = online.update(u, y)
        >>> before = online.estimate()
        >>> _ = online.update(2.0, 1e8)  # a glitch
        >>> online.revert()
        >>> online.estimate() == before, online.n_samples
        (True, 4)
        """
        self._revert()

    def snapshot(self) -> dict[str, Any]:
        """The estimate alone (``theta``, ``P``, where a forgetting schedule stands),
        JSON-ready, for :meth:`rewind`."""
        return {name: _encode(getattr(self, name)) for name in self._estimate}

    def rewind(self, snapshot: dict[str, Any]) -> None:
        """Put back an estimate of :meth:`snapshot`; the memory of the recent samples
        stays current (the samples after a rewind keep their true lags)."""
        for name in self._estimate:
            _decode_into(self, name, snapshot[name])

    def _hold(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """A sample taken into the memory, not learned from: the step, then the
        estimate put back (backends that can hold without a step override this)."""
        prediction = self._step(u, y)
        self._revert()
        return prediction

    @abstractmethod
    def _revert(self) -> None:
        """Put back the estimate from before the last step (:meth:`revert`)."""

    def _sample(self, u: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        """One sample as flat float arrays, checked (the lean test first, the full
        explanation of :meth:`_check` only when it fails)."""
        u = np.asarray(u, dtype=float).reshape(-1)
        y = np.asarray(y, dtype=float).reshape(-1)
        values = u.tolist() + y.tolist()
        if u.size != self._nu or y.size != self._ny or not all(map(math.isfinite, values)):
            self._check(u[None, :], y[None, :])  # raises the full explanation
        return u, y

    def parameters(self) -> dict[str, Any]:
        """The current estimate by name, as in model files (:func:`model_parameters`)."""
        return model_parameters(self.model())

    @abstractmethod
    def model(self) -> Any:
        """The model of the current estimate (the class the offline fit returns)."""

    @abstractmethod
    def estimate(self) -> dict[str, float]:
        """The recursion's parameter vector in the data's units, by entry name: for the
        papers' methods in the order and with the names of the offline fit's
        ``history["names"]`` (B4, A6: ``f_0``, ``a_1``, ``m_left*c_left``..), for ARX
        ``a[y][y][1]``.. as :meth:`~blockid.models.ARX.parameter_names`. Unlike
        :meth:`model` it exists whatever the values (a backlash read-back needs
        positive slopes)."""

    @abstractmethod
    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Run the chunk, commit the state on success; predictions (N, ny)."""

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """One checked sample, ``u`` (nu,) and ``y`` (ny,): the lean per-sample path
        (the same kernels on preallocated buffers) where there is one."""
        return self._learn(u[None, :], y[None, :])[0]

    def _check(self, u: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        nu, ny = len(self.names.inputs), len(self.names.outputs)
        u = np.asarray(u, dtype=float)
        y = np.asarray(y, dtype=float)
        u = u[:, None] if u.ndim == 1 else u
        y = y[:, None] if y.ndim == 1 else y
        if u.ndim != 2 or y.ndim != 2 or u.shape[1] != nu or y.shape[1] != ny:
            raise DataError(
                f"online learning of a model with {nu} input(s) and {ny} output(s) got arrays "
                f"of shape {u.shape} and {y.shape}"
            )
        if u.shape[0] != y.shape[0]:
            raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
            raise DataError(
                "the chunk contains NaN or inf; online learning needs every sample (drop or "
                "fill missing samples before feeding them)"
            )
        return u, y

    def _diverged(self, method: str, index: int, reason: str) -> EstimationError:
        sample = self.n_samples + index
        summary = (
            f"{method} diverged at sample {sample} (counted from the first sample learned "
            f"online): {reason}"
        )
        error = EstimationError(
            f"{summary}. The estimator is left as it was before this call; go on with the "
            "next samples or stop. See docs/convergence.md"
        )
        error.sample = sample
        error.summary = summary  # without the advice (a stream gives its own)
        return error


# ---------------------------------------------------------------------- papers A, B
def _encode(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return {"shape": list(value.shape), "values": value.ravel().tolist()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def _decode_into(owner: Any, name: str, saved: Any) -> None:
    current = getattr(owner, name)
    if isinstance(current, np.ndarray):
        values = np.asarray(saved["values"], dtype=current.dtype).reshape(saved["shape"])
        if values.shape == current.shape:
            np.copyto(current, values)
        else:
            setattr(owner, name, values)
        return
    setattr(owner, name, type(current)(saved))


class _PaperOnline(OnlineEstimator):
    """Shared state handling of the two internal-variable recursions (B5, A6–A8).

    The window ``self._buf`` holds the last ``L`` samples of every signal the kernel
    reads (rows: ``self._rows``) and one free slot for the per-sample path; before the
    record it holds the values the offline pass assumes there (0, or the backlash at
    rest). Subclasses set the kernel call.
    """

    _rows: tuple[str, ...]  # signals in the window, the kernel's order
    _state = ("n_samples", "theta", "P", "_buf", "_y_max")

    def _setup(self, algorithm: Any, theta0: np.ndarray, mu: float, lag: int) -> None:
        n = len(algorithm.names)
        self.algorithm = algorithm  # names, n0, unit maps, reasons, read-back
        self.theta = theta0  # estimate on the scaled signals
        self.P = mu * np.eye(n)  # covariance P
        self.L = lag  # samples of history the kernel reaches back to
        self._buf = np.zeros((len(self._rows), lag + 1))  # history | one free slot
        self._err1 = np.full(lag + 1, np.nan)  # a-priori error of the per-sample path
        self._y_max = 0.0  # largest |y| (scaled) seen: the x_hat divergence limit
        self._bak = (theta0.copy(), self.P.copy())  # theta, P before a step (roll-back)
        self._y_max_bak = 0.0  # max|y| before a step (revert)
        self._views = [self._buf[i] for i in range(len(self._rows))]  # rows of the window

    @abstractmethod
    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        """Run the kernel on ``arrays`` (window then chunk; ``single``: the window's
        free slot holds the one new sample) with the first update at ``n0``, ``count``
        updates before it and ``max|y| = y_max``; returns (status, reason)."""

    def _first(self, us: np.ndarray) -> None:
        """Hook before the first sample (the backlash's rest state)."""

    def _n0(self) -> tuple[int, int]:
        """Index of the first update in the window + chunk arrays, and the number of
        updates before it (where a forgetting schedule stands)."""
        n0 = self.algorithm.n0
        return self.L + max(n0 - self.n_samples, 0), max(self.n_samples - n0, 0)

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        us, ys = u[:, 0] / self.su, y[:, 0] / self.sy
        if self.n_samples == 0:
            self._first(us)
        L, m = self.L, us.size
        hist = self._buf[:, :L]
        arrays = [np.empty(L + m) for _ in self._rows]
        for i, arr in enumerate(arrays):
            arr[:L] = hist[i]
        arrays[0][L:] = us
        arrays[1][L:] = ys
        err = np.full(L + m, np.nan)
        n0, count = self._n0()
        y_max = max(self._y_max, float(np.max(np.abs(ys))))
        theta, P = self.theta.copy(), self.P.copy()
        status, reason = self._run(theta, P, arrays, n0, count, err, y_max)
        if status != _kr.OK:
            raise self._diverged(self.algorithm.method, status - L, self.algorithm.reasons[reason])
        np.copyto(self._bak[0], self.theta)
        np.copyto(self._bak[1], self.P)
        self._y_max_bak = self._y_max
        self.theta, self.P, self._y_max = theta, P, y_max
        for i, arr in enumerate(arrays):
            hist[i] = arr[m:]
        self.n_samples += m
        return ((ys - err[L:]) * self.sy)[:, None]

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        us, ys = float(u[0]) / self.su, float(y[0]) / self.sy
        buf, L = self._buf, self.L
        if self.n_samples == 0:
            self._first(np.array([us]))
        buf[0, L] = us
        buf[1, L] = ys
        self._err1[L] = np.nan
        n0, count = self._n0()
        y_max = ys if ys > self._y_max else -ys if -ys > self._y_max else self._y_max
        theta_bak, P_bak = self._bak
        np.copyto(theta_bak, self.theta)
        np.copyto(P_bak, self.P)
        status, reason = self._run(
            self.theta, self.P, self._views, n0, count, self._err1, y_max, single=True
        )
        if status != _kr.OK:
            np.copyto(self.theta, theta_bak)
            np.copyto(self.P, P_bak)
            raise self._diverged(self.algorithm.method, 0, self.algorithm.reasons[reason])
        self._y_max_bak, self._y_max = self._y_max, y_max
        buf[:, :L] = buf[:, 1:]
        self.n_samples += 1
        return np.array([(ys - self._err1[L]) * self.sy])

    def _revert(self) -> None:
        np.copyto(self.theta, self._bak[0])
        np.copyto(self.P, self._bak[1])
        self._y_max = self._y_max_bak

    def model(self) -> Any:
        theta = self.algorithm.to_data_units(self.theta)
        return self._read_back(theta)

    def estimate(self) -> dict[str, float]:
        theta = self.algorithm.to_data_units(self.theta)
        return dict(zip(self.algorithm.names, theta.tolist(), strict=True))

    def _read_back(self, theta: np.ndarray) -> Any:
        return self.algorithm.model(theta, self.names)

    def _theta0(self, opts: dict[str, Any], initial_vector_data: Any) -> np.ndarray:
        """``theta(0)`` on the scaled signals, as :func:`fit_recursive` makes it."""
        names = self.algorithm.names
        value = opts["initial_parameters"] if initial_vector_data is None else initial_vector_data
        theta = initial_vector(value, len(names), names)
        if np.ndim(value) != 0:  # given in the data's units
            theta = self.algorithm.from_data_units(theta)
        return np.ascontiguousarray(theta, dtype=float)


def _signals(scales: Any) -> Signals:
    """The unit maps of the recursion (one dummy record: the divergence limit the
    algorithm derives from the record is replaced by the running one)."""
    su, sy = scales if scales is not None else (1.0, 1.0)
    one = np.zeros(1)
    return Signals([("online", one, one)], (0.0, su), (0.0, sy), scales is not None)


def _orders_from(initial: Any, opts: dict[str, Any], keys: tuple[str, ...]) -> dict[str, Any]:
    """Orders not given in ``opts`` taken from the starting model."""
    if initial is None:
        return opts
    found = {"na": initial.na, "nb": initial.nb, "nk": initial.nk}
    if "r1" in keys and initial.input_block is not None:
        found["r1"] = initial.input_block.order
    if "r2" in keys and initial.output_block is not None:
        found["r2"] = initial.output_block.degree
    return {**{k: v for k, v in found.items() if k in keys}, **opts}


class _OnlineKeyTerm(_PaperOnline):
    _state = (*_PaperOnline._state, "_limits")

    """Paper B's key-term RLS (B5) online; window rows ``u, y, w_hat, x_hat``."""

    _rows = ("u", "y", "w", "x")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        scales = _paper_scales(scales)
        keys = ("na", "nb", "nk", "r1", "r2", "forgetting", "initial_covariance")
        keys += ("initial_parameters",)
        opts = _defaults(fit_key_term_rls, _orders_from(initial, opts, keys), keys)
        has_in, has_out = KEY_TERM_STRUCTURES[structure]
        na = int_at_least("na", opts["na"], 0)
        nb = int_at_least("nb", opts["nb"], 1)
        nk = int_at_least("nk", opts["nk"], 0)
        r1 = checked("r1", opts["r1"]) if has_in else 0
        r2 = int_at_least("r2", opts["r2"], 2) if has_out else 1  # key-term's own minimum
        mu = checked("initial_covariance", opts["initial_covariance"])
        schedule = ForgettingSchedule.parse(opts["forgetting"])
        signals = _signals(scales)
        algorithm = KeyTermRLS(structure, (na, nb, nk, r1, r2), schedule, mu, signals)
        self.su, self.sy = signals.u_map[1], signals.y_map[1]  # scales of u and y
        self.schedule = schedule  # lambda over the updates since the record start
        self.structure = structure
        lag = largest_lag(na, nb, nk)
        self.algorithm = algorithm
        theta0 = self._theta0(opts, None if initial is None else self._vector(initial))
        self._setup(algorithm, theta0, mu, lag)
        # kernel arguments of the per-sample path, reused
        self._orders = np.array([r1, nb, na, r2, nk, has_in, has_out, 0, 1, lag], dtype=np.int64)
        self._limits = np.array([algorithm.limits[0], 0.0])
        self._lam1 = np.ones(lag + 1)
        self._no_hist = np.zeros((0, len(algorithm.names)))
        n = len(algorithm.names)
        self._saved = np.empty(n + n * n)  # theta and P before a step (roll-back)
        self._saved[:n], self._saved[n:] = self.theta, self.P.ravel()
        self._bak = (self._saved[:n], self._saved[n:].reshape(n, n))  # the same, as views

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The lean per-sample path: one compiled call (:func:`key_term_step`)."""
        if self.n_samples == 0:
            return super()._step(u, y)
        us, ys = float(u[0]) / self.su, float(y[0]) / self.sy
        y_max = self._y_max
        if abs(ys) > y_max:  # the divergence limit grows with max|y| (as offline)
            self._limits[1] = 1e6 * (1.0 + abs(ys))
        n0, count = self._n0()
        lam = _schedule_factor(self.schedule, count) if n0 <= self.L else 1.0
        status, reason, e = _kk.key_term_step(
            self.theta,
            self.P,
            self._buf,
            us,
            ys,
            lam,
            n0,
            self._orders,
            self._limits,
            self._saved,
            self._no_hist,
        )
        if status != _kr.OK:
            self._limits[1] = 1e6 * (1.0 + y_max)
            raise self._diverged(self.algorithm.method, 0, self.algorithm.reasons[reason])
        self._y_max_bak, self._y_max = y_max, max(y_max, abs(ys))
        self.n_samples += 1
        return np.array([(ys - e) * self.sy])

    def _revert(self) -> None:
        super()._revert()
        self._limits[1] = 1e6 * (1.0 + self._y_max)  # the limit follows max|y|

    def _vector(self, model: Any) -> np.ndarray:
        """``theta`` of a model in the data's units, in the order of (B4)."""
        has_in, has_out = self.algorithm.has_in, self.algorithm.has_out
        na, nb, nk, r1, r2 = self.algorithm.orders
        if (model.na, model.nb, model.nk) != (na, nb, nk):
            raise ParameterError(
                f"initial has orders na={model.na}, nb={model.nb}, nk={model.nk}, not "
                f"na={na}, nb={nb}, nk={nk}"
            )
        parts = []
        if has_in:
            block = model.input_block
            if getattr(block, "kind", None) != "two-segment-polynomial" or block.order != r1:
                raise ParameterError(
                    f"initial's input block must be a two-segment polynomial of order {r1}"
                )
            parts += [block.f, block.p, model.b[1:]]
        else:
            parts.append(model.b)
        parts.append(model.a)
        if has_out:
            block = model.output_block
            coef = getattr(block, "coefficients", None)
            if coef is None or block.degree != r2 or block.parameters.get("constant", False):
                raise ParameterError(
                    f"initial's output block must be a polynomial of degree {r2} without constant"
                )
            parts.append(np.asarray(coef)[1:])
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        u, y, w, x = arrays
        N = u.size
        if single:  # lam of the window's free slot only
            lam = self._lam1
            if n0 <= self.L:
                lam[self.L] = _schedule_factor(self.schedule, count)
        else:
            lam = np.ones(N)
            lam[n0:] = self.schedule.factors(count, max(N - n0, 0))
        orders = self._orders
        orders[7] = n0
        limits = self._limits
        limits[1] = 1e6 * (1.0 + y_max)  # as offline, with max|y| so far
        return _kk.key_term_run(theta, P, u, y, lam, orders, limits, w, x, self._no_hist, err)


class _OnlineKeyTermChannels(OnlineEstimator):
    """Paper B's key-term RLS of several inputs (one output) online
    (:mod:`blockid.fitting.key_term_channels`): the kernel continued from a window of
    the last ``L`` samples of every channel's basis functions, the output and the
    internal estimates ``w_hat``, ``x_hat``; the inputs and ``x_hat`` seen so far are the
    blocks' ranges. Ends with the estimate of ``fit_key_term_channels(.., passes=1)``
    on the same scales (``scales=(input_scale, output_scale)``, or ``normalize=False``
    without them), bit for bit."""

    _state = ("n_samples", "theta", "P", "_phi", "_y", "_w", "_x", "_y_max", "_ranges")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        from blockid.fitting.key_term_channels import checked_scales, key_term_algorithm

        super().__init__(names)
        if initial is not None:
            raise ParameterError(
                "key-term RLS of several inputs learns online from no model (its model file "
                "holds the realised state space, not the recursion's parameters); leave "
                "--model out, or give initial_parameters",
                parameter="initial",
            )
        if len(self.names.outputs) != 1:
            raise ParameterError(
                f"key-term RLS identifies one output at a time ({len(self.names.outputs)} "
                "given): learn each output with its own stream, or use --method rls "
                "(Hammerstein, several outputs)",
                parameter="outputs",
            )
        keys = ("input_block", "output_block", "na", "nb", "nk", "forgetting")
        keys += ("initial_covariance", "initial_parameters")
        from blockid.fitting.key_term_channels import fit_key_term_channels

        values = _defaults(fit_key_term_channels, opts, keys)
        if structure in KEY_TERM_STRUCTURES:  # a chain structure: paper B's blocks
            has_in, has_out = KEY_TERM_STRUCTURES[structure]
            r = _defaults(fit_key_term_rls, opts, ("r1", "r2"))
            values["input_block"] = f"two-segment-polynomial:degree={r['r1']}" if has_in else None
            values["output_block"] = f"polynomial:degree={r['r2']}" if has_out else None
        elif "input_block" not in opts and "output_block" not in opts:
            values["input_block"] = "two-segment-polynomial:degree=3"  # as offline
            values["output_block"] = "polynomial:degree=3"
        algorithm = key_term_algorithm(self.names.inputs, self.names.outputs[0], values)
        if scales is not None:
            su, sy = checked_scales(scales, len(self.names.inputs))
            algorithm.set_scales(algorithm.given_scales(su), sy, 0.0)
        self.algorithm = algorithm
        n = len(algorithm.names)
        value = values["initial_parameters"]
        theta = initial_vector(value, n, algorithm.names)
        if np.ndim(value) != 0:  # given in the data's units
            theta = algorithm.from_data_units(theta)
        self.theta = np.ascontiguousarray(theta, dtype=float)
        self.P = algorithm.mu * np.eye(n)
        self.L = L = algorithm.n0
        m, nf = len(self.names.inputs), algorithm.nf
        self._phi, self._y = np.zeros((L, m, nf)), np.zeros(L)
        self._w, self._x = np.zeros((L, m)), np.zeros(L)
        self._y_max = 0.0
        self._ranges = np.array([[np.inf, -np.inf]] * (m + 1))  # inputs, then x_hat
        self._previous = (self.theta, self.P, self._y_max, self._ranges.copy())  # revert

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        alg, L, N = self.algorithm, self.L, u.shape[0]
        ys = y[:, 0] / alg.sy
        phi = np.concatenate([self._phi, alg._functions(u) / alg.scales])
        yy = np.concatenate([self._y, ys])
        w = np.concatenate([self._w, np.empty((N, self._w.shape[1]))])
        x = np.concatenate([self._x, np.empty(N)])
        n0 = L + max(alg.n0 - self.n_samples, 0)
        count = max(self.n_samples - alg.n0, 0)
        lam = np.ones(L + N)
        lam[n0:] = alg.schedule.factors(count, max(L + N - n0, 0))
        y_max = max(self._y_max, float(np.max(np.abs(ys))))
        limits = np.array([alg.limits[0], 1e6 * (1.0 + y_max)])
        orders = alg.kernel_orders(n0, 1, L)
        err = np.full(L + N, np.nan)
        theta, P = self.theta.copy(), self.P.copy()
        status, reason = _kc.key_term_channels_run(
            theta, P, phi, yy, lam, orders, alg.delays, limits, w, x,
            np.zeros((0, theta.size)), err,
        )  # fmt: skip
        if status != _kr.OK:
            raise self._diverged(alg.method, status - L, alg.reasons[reason])
        self._previous = (self.theta, self.P, self._y_max, self._ranges.copy())
        self.theta, self.P, self._y_max = theta, P, y_max
        self._phi, self._y, self._w, self._x = phi[N:], yy[N:], w[N:], x[N:]
        self._ranges[:-1, 0] = np.minimum(self._ranges[:-1, 0], u.min(axis=0))
        self._ranges[:-1, 1] = np.maximum(self._ranges[:-1, 1], u.max(axis=0))
        if alg.has_out:
            self._ranges[-1] = [min(self._ranges[-1, 0], float(x[L:].min()) * alg.sy),
                                max(self._ranges[-1, 1], float(x[L:].max()) * alg.sy)]  # fmt: skip
        self.n_samples += N
        return ((ys - err[L:]) * alg.sy)[:, None]

    def _revert(self) -> None:
        self.theta, self.P, self._y_max, ranges = self._previous
        np.copyto(self._ranges, ranges)

    def rewind(self, snapshot: dict[str, Any]) -> None:
        self.theta, self.P = self.theta.copy(), self.P.copy()  # _previous keeps its own
        super().rewind(snapshot)

    def model(self) -> Any:
        alg = self.algorithm
        if np.all(np.isfinite(self._ranges[:-1])):
            alg.u_range = self._ranges[:-1].copy()
        alg.x_range = self._ranges[-1].copy()
        return alg.model(alg.to_data_units(self.theta), None)

    def estimate(self) -> dict[str, float]:
        theta = self.algorithm.to_data_units(self.theta)
        return dict(zip(self.algorithm.names, theta.tolist(), strict=True))


class _OnlineBacklash(_PaperOnline):
    """Paper A's AW-RLS (A6–A8) online; window rows ``u, v, x_hat, f1_hat, f2_hat``."""

    _rows = ("u", "v", "x", "f1", "f2")

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        scales = _paper_scales(scales)
        keys = ("na", "nb", "nk", "eps1", "eps2", "initial_covariance", "initial_parameters")
        opts = _defaults(fit_backlash_aw_rls, _orders_from(initial, opts, keys), keys)
        na = int_at_least("na", opts["na"], 0)
        nb = int_at_least("nb", opts["nb"], 1)
        nk = int_at_least("nk", opts["nk"], 1)
        eps = (checked("eps1", opts["eps1"]), checked("eps2", opts["eps2"]))
        mu = checked("initial_covariance", opts["initial_covariance"])
        signals = _signals(scales)
        algorithm = BacklashAWRLS((na, nb, nk), eps, signals)
        self.su, self.sy = signals.u_map[1], signals.y_map[1]
        self.algorithm = algorithm
        lag = max(largest_lag(na, nb, nk), nk + 1)  # (A6) reaches x(t - nk - 1)
        theta0 = self._theta0(opts, None if initial is None else self._vector(initial))
        self._setup(algorithm, theta0, mu, lag)
        self._orders = np.array([nb, na, nk, 0, 1, lag], dtype=np.int64)
        self._params = np.array([eps[0], eps[1], 0.0])
        self._no_hist = np.zeros((0, len(algorithm.names)))

    def _vector(self, model: Any) -> np.ndarray:
        na, nb, nk = self.algorithm.orders
        if (model.na, model.nb, model.nk) != (na, nb, nk):
            raise ParameterError(
                f"initial has orders na={model.na}, nb={model.nb}, nk={model.nk}, not "
                f"na={na}, nb={nb}, nk={nk}"
            )
        return np.concatenate((model.input_block.to_theta(), model.b[1:], model.a))

    def _first(self, us: np.ndarray) -> None:
        # before the record the backlash rests mid-dead-band at u(0), as offline
        self._buf[2, : self.L] = _kb.backlash_rest(self.theta, us[0])

    def _run(self, theta, P, arrays, n0, count, err, y_max, single=False):
        u, v, x, f1, f2 = arrays
        orders = self._orders
        orders[3] = n0
        params = self._params
        params[2] = 1e6 * (1.0 + y_max)
        return _kb.backlash_aw_rls_run(
            theta, P, u, v, orders, params, x, f1, f2, self._no_hist, err
        )

    def _read_back(self, theta: np.ndarray) -> Any:
        if not np.all(np.isfinite(theta)):  # pragma: no cover - the kernel checks steps
            raise EstimationError("AW-RLS: the online estimate is not finite")
        return self.algorithm.read_back(theta, self.names)


# ---------------------------------------------------------------------- ARX
class _Item:
    """A dict seen as an object (for :func:`_decode_into`)."""

    def __init__(self, d: dict[str, Any]) -> None:
        object.__setattr__(self, "_d", d)

    def __getattr__(self, name: str) -> Any:
        return self._d[name]

    def __setattr__(self, name: str, value: Any) -> None:
        self._d[name] = value


class _OnlineARX(OnlineEstimator):
    """ARX by RLS, AW-RLS or H-RLS online: one recursion per output, as
    :func:`~blockid.fitting.arx.fit_arx` runs them, on the regressor columns divided by
    the given signal scales (or by nothing)."""

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        super().__init__(names)
        keys = ("na", "nb", "nk", "forgetting", "initial_covariance", "eps1", "eps2")
        if initial is not None:
            given = {"na": initial.na, "nb": initial.nb, "nk": initial.nk}
            opts = {**{k: v.tolist() for k, v in given.items()}, **opts}
        opts = _defaults(fit_arx, opts, keys)
        self.method = method
        self.schedule = ForgettingSchedule.parse(opts["forgetting"])
        self._last_factor = np.full(1, self.schedule.values[-1])
        inputs, outputs = names
        self.template = ARX(inputs, outputs, opts["na"], opts["nb"], opts["nk"])
        model = self.template
        if initial is not None and (
            initial.inputs != model.inputs or initial.outputs != model.outputs
        ):
            raise ParameterError(
                f"initial has signals {list(initial.inputs)} -> {list(initial.outputs)}, "
                f"not {list(model.inputs)} -> {list(model.outputs)}"
            )
        scaling = "none" if scales is None else signal_scales(scales, len(inputs), len(outputs))
        self.L = model.max_lag  # samples of history the regressors reach back to
        self._u = np.zeros((0, len(inputs)))  # the last L samples (fewer at the start)
        self._y = np.zeros((0, len(outputs)))
        self.outputs = []  # per output: [scale, theta, P, perm, bounds, updates]
        for i in range(len(outputs)):
            n = model.n_parameters(i)
            est = make_estimator(  # the offline defaults of every method
                method,
                forgetting=self.schedule,
                initial_covariance=opts["initial_covariance"],
                eps1=opts["eps1"],
                eps2=opts["eps2"],
                groups=model.hierarchical_groups(i),
            )
            scale = regressor_scale(model, i, scaling)
            theta = np.full(n, float(est.initial_parameters))
            if initial is not None:
                theta = initial.parameter_vector(i) * scale
            groups = model.hierarchical_groups(i) if method == "hierarchical-rls" else [range(n)]
            perm = np.array([c for g in groups for c in g], dtype=np.int64)
            bounds = np.cumsum([0] + [len(g) for g in groups]).astype(np.int64)
            trace = getattr(est, "max_covariance_trace", None) or est.initial_covariance * n
            self.outputs.append(
                {
                    "scale": scale,  # divisors of the regressor columns
                    "theta": np.ascontiguousarray(theta[perm]),  # in group order
                    "P": float(est.initial_covariance) * np.eye(n),
                    "perm": perm,  # column order of the kernel (H-RLS groups contiguous)
                    "bounds": bounds,  # H-RLS group boundaries
                    "trace": float(trace),  # trace bound of P while lambda < 1
                    "eps": (float(getattr(est, "eps1", 0.0)), float(getattr(est, "eps2", 0.0))),
                    "updates": 0,  # updates so far (where the schedule stands)
                }
            )
        self._previous = self._estimates()  # per output before the last step (revert)

    def _estimates(self) -> list[tuple[np.ndarray, np.ndarray, int]]:
        """``(theta, P, updates)`` of every output, by reference (a step replaces the
        arrays, never writes into them)."""
        return [(o["theta"], o["P"], o["updates"]) for o in self.outputs]

    def _revert(self) -> None:
        for out, (theta, P, updates) in zip(self.outputs, self._previous, strict=True):
            out["theta"], out["P"], out["updates"] = theta, P, updates

    @property
    def n_parameters(self) -> int:
        return max(int(o["theta"].size) for o in self.outputs)

    def snapshot(self) -> dict[str, Any]:
        return {"outputs": self.state()["outputs"]}

    def rewind(self, snapshot: dict[str, Any]) -> None:
        for out, saved in zip(self.outputs, snapshot["outputs"], strict=True):
            for key in ("theta", "P"):  # fresh arrays: _previous keeps its own
                out[key] = np.asarray(saved[key]["values"], dtype=float).reshape(
                    saved[key]["shape"]
                )
            out["updates"] = int(saved["updates"])

    def state(self) -> dict[str, Any]:
        out = {name: _encode(getattr(self, name)) for name in ("n_samples", "_u", "_y")}
        out["outputs"] = [
            {"theta": _encode(o["theta"]), "P": _encode(o["P"]), "updates": o["updates"]}
            for o in self.outputs
        ]
        return out

    def restore(self, state: dict[str, Any]) -> _OnlineARX:
        if len(state.get("outputs", ())) != len(self.outputs):
            raise ParameterError("the saved learner state is of another model (its outputs differ)")
        for name in ("n_samples", "_u", "_y"):
            _decode_into(self, name, state[name])
        for out, saved in zip(self.outputs, state["outputs"], strict=True):
            for key in ("theta", "P"):
                _decode_into(_Item(out), key, saved[key])
            out["updates"] = int(saved["updates"])
        return self

    def _lean_regressors(self) -> None:
        """For the per-sample path: where every regressor column of every output sits in
        the vector ``[y(t-L) .. y(t), u(t-L) .. u(t)]`` (rows flattened), its sign and
        its scale, in the kernel's column order."""
        model, L = self.template, self.L
        ny, nu = len(model.outputs), len(model.inputs)
        for i, out in enumerate(self.outputs):
            index, sign = [], []
            for j in range(ny):
                for k in range(1, model.na[i, j] + 1):
                    index.append((L - k) * ny + j)
                    sign.append(-1.0)
            for m in range(nu):
                for lag in range(model.nb[i, m]):
                    index.append((L + 1) * ny + (L - model.nk[i, m] - lag) * nu + m)
                    sign.append(1.0)
            perm = out["perm"]
            out["index"] = np.asarray(index, dtype=np.int64)[perm]
            out["sign"] = np.asarray(sign)[perm]
            out["divisor"] = np.asarray(out["scale"], dtype=float)[perm]

    def _step(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """One sample without building regressor matrices: the regressor rows gathered
        from the last ``L`` samples and this one, the same kernels (bit-identical to
        :meth:`_learn` on a one-sample chunk)."""
        L = self.L
        if L == 0 or self._u.shape[0] < L:  # still filling the regressor
            return self._learn(u[None, :], y[None, :])[0]
        if "index" not in self.outputs[0]:
            self._lean_regressors()
        ny = y.shape[0]
        V = np.concatenate((self._y.ravel(), y, self._u.ravel(), u))
        pred = np.full(ny, np.nan)
        new = []
        for i, out in enumerate(self.outputs):
            if out["theta"].size == 0:
                new.append(None)
                continue
            # negated, then divided, as the chunk path: the same bits
            Phi = (out["sign"] * V[out["index"]] / out["divisor"])[None, :]
            target = y[i : i + 1].copy()
            theta, P = out["theta"].copy(), out["P"].copy()
            E = np.empty(1)
            status = self._kernel(out, Phi, target, theta, P, E)
            if status != _kr.OK or not np.isfinite(theta).all():
                raise self._diverged(
                    f"{_ARX_NAMES[self.method]} of output {self.template.outputs[i]!r}",
                    0,
                    "the covariance or the estimate became non-finite or lost positive "
                    "definiteness",
                )
            pred[i] = target[0] - E[0]
            new.append((theta, P))
        self._previous = self._estimates()
        for out, state in zip(self.outputs, new, strict=True):  # commit every output
            if state is not None:
                out["theta"], out["P"] = state
                out["updates"] += 1
        n_y = (L + 1) * ny
        self._y = V[ny:n_y].reshape(L, ny)
        self._u = V[n_y + u.shape[0] :].reshape(L, u.shape[0])
        self.n_samples += 1
        return pred

    def _hold(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The sample into the window, no kernel: the prediction ``phi^T theta`` of
        every output (NaN while the window fills), the estimate untouched."""
        L, ny = self.L, y.shape[0]
        pred = np.full(ny, np.nan)
        if self._u.shape[0] < L:  # still filling the regressor
            self._u = np.vstack((self._u, u[None, :]))
            self._y = np.vstack((self._y, y[None, :]))
        else:
            if "index" not in self.outputs[0]:
                self._lean_regressors()
            V = np.concatenate((self._y.ravel(), y, self._u.ravel(), u))
            with np.errstate(over="ignore", invalid="ignore"):  # a glitch may overflow
                for i, out in enumerate(self.outputs):
                    if out["theta"].size:
                        phi = out["sign"] * V[out["index"]] / out["divisor"]
                        pred[i] = float(phi @ out["theta"])
            n_y = (L + 1) * ny
            self._y = V[ny:n_y].reshape(L, ny)
            self._u = V[n_y + u.shape[0] :].reshape(L, u.shape[0])
        self.n_samples += 1
        return pred

    def _kernel(self, out: dict, Phi: np.ndarray, target: np.ndarray, theta, P, E) -> int:
        m = target.size
        if self.method == "aw-rls":
            eps1, eps2 = out["eps"]
            return _kr.aw_rls_run(theta, P, Phi, target, eps1, eps2, np.empty(m), E)
        if m == 1 and out["updates"] >= self.schedule.settled_after:  # the per-sample path
            lam = self._last_factor
        else:
            lam = self.schedule.factors(out["updates"], m)
        if self.method == "rls":
            return _kr.rls_run(theta, P, Phi, target, lam, out["trace"], E)
        return _kr.hierarchical_rls_run(theta, P, Phi, target, out["bounds"], lam, out["trace"], E)

    def _learn(self, u: np.ndarray, y: np.ndarray) -> np.ndarray:
        m = u.shape[0]
        U, Y = np.vstack((self._u, u)), np.vstack((self._y, y))
        pred = np.full(y.shape, np.nan)
        new = []
        for i, out in enumerate(self.outputs):
            if out["theta"].size == 0:
                new.append(None)
                continue
            Phi, target = self.template.regressors(U, Y, i)
            Phi = np.ascontiguousarray((Phi / out["scale"])[:, out["perm"]])
            theta, P = out["theta"].copy(), out["P"].copy()
            E = np.empty(target.size)
            status = self._kernel(out, Phi, np.ascontiguousarray(target), theta, P, E)
            if status != _kr.OK or not np.all(np.isfinite(theta)):
                row = status if status != _kr.OK else target.size - 1
                raise self._diverged(
                    f"{_ARX_NAMES[self.method]} of output {self.template.outputs[i]!r}",
                    m - target.size + row,
                    "the covariance or the estimate became non-finite or lost positive "
                    "definiteness",
                )
            pred[m - target.size :, i] = target - E
            new.append((theta, P, target.size))
        self._previous = self._estimates()
        for out, state in zip(self.outputs, new, strict=True):  # commit every output
            if state is not None:
                out["theta"], out["P"] = state[0], state[1]
                out["updates"] += state[2]
        self._u, self._y = U[-self.L :], Y[-self.L :]
        self.n_samples += m
        return pred

    def estimate(self) -> dict[str, float]:
        """The recursion's coefficients by name, as the ARX it fits names them (for the
        block model on an ARX core, ``b[y1][u1[coefficients_2]][0]``: the product of a
        block's and the core's coefficients)."""
        arx = self._arx()
        return {
            name: float(value)
            for i in range(len(arx.outputs))
            for name, value in zip(arx.parameter_names(i), arx.parameter_vector(i), strict=True)
        }

    def model(self) -> Any:
        return self._arx()

    def _arx(self) -> ARX:
        """The ARX of the current estimate, on the regressors' own signals."""
        t = self.template
        model = ARX(t.inputs, t.outputs, t.na, t.nb, t.nk)
        for i, out in enumerate(self.outputs):
            if out["theta"].size:
                theta = np.empty_like(out["theta"])
                theta[out["perm"]] = out["theta"]
                model.set_parameter_vector(i, theta / out["scale"])
        return model


class _OnlineBlockARX(_OnlineARX):
    """A Hammerstein model of several inputs and outputs on an ARX core, online: the ARX
    recursion on the input blocks' basis functions and a constant
    (:mod:`blockid.fitting.block_arx`),
    split into blocks and core when :meth:`model` is asked for. The ranges the inputs
    covered so far are the blocks' ranges (a polynomial continues along its tangent
    beyond them)."""

    def __init__(self, structure, method, opts, names, scales, initial) -> None:
        if initial is not None:
            raise ParameterError(
                "a block model on an ARX core learns online from no model (its regression "
                "holds products of block and core coefficients that a model file does not "
                "give); leave --model out",
                parameter="initial",
            )
        opts = dict(opts)
        self.basis = input_basis(opts.pop("input_block", None), opts.pop("output_block", None))
        inputs, outputs = (tuple(n) for n in names)
        orders = _defaults(fit_block_arx, opts, ("na", "nb", "nk"))
        na, nb, nk = scalar_orders(orders["na"], orders["nb"], orders["nk"])
        NA, NB, NK = regression_orders(len(outputs), len(inputs), self.basis.size, na, nb, nk)
        opts.update(na=NA.tolist(), nb=NB.tolist(), nk=NK.tolist())
        if scales is not None:  # a basis function's column is scaled by its value at the
            # input's scale (a power p by s^p), the constant by 1
            su = np.broadcast_to(np.asarray(scales[0], dtype=float), (len(inputs),))
            parts = [np.abs(self.basis.functions(np.array([s])))[0] for s in su]
            su = np.r_[np.concatenate(parts), 1.0]
            su[su == 0] = 1.0
            scales = (su, scales[1])
        virtual = self.basis.inputs(inputs)
        super().__init__("arx", method, opts, (virtual, outputs), scales, None)
        self.names = _Names(inputs, outputs)
        self._nu = len(inputs)
        self._range = np.tile([np.inf, -np.inf], (len(inputs), 1))

    def state(self) -> dict[str, Any]:
        return {**super().state(), "_range": _encode(self._range)}

    def restore(self, state: dict[str, Any]) -> _OnlineBlockARX:
        if "_range" not in state:
            raise ParameterError("the saved learner state is of another model (no input ranges)")
        super().restore(state)
        _decode_into(self, "_range", state["_range"])
        return self

    def _widen(self, u: np.ndarray) -> None:
        if u.shape[0]:
            self._range[:, 0] = np.minimum(self._range[:, 0], u.min(axis=0))
            self._range[:, 1] = np.maximum(self._range[:, 1], u.max(axis=0))

    def partial_fit(self, u: Any, y: Any) -> _OnlineBlockARX:
        u, y = self._check(u, y)
        learned = self._learn(self.basis.expanded(u), y) if u.shape[0] else np.zeros_like(y)
        self.predictions_ = learned
        self._widen(u)
        return self

    def update(self, u: Any, y: Any, learn: bool = True) -> np.ndarray:
        u, y = self._sample(u, y)
        expanded = self.basis.expanded(u[None, :])[0]
        if not learn:  # a held sample does not widen the blocks' ranges
            return self._hold(expanded, y)
        prediction = self._step(expanded, y)
        self._widen(u[None, :])
        return prediction

    def model(self) -> Any:
        seen = np.all(np.isfinite(self._range))
        model, _ = arx_core_model(
            self._arx(), self.names.inputs, self.basis,
            input_range=self._range if seen else None,
        )  # fmt: skip
        return model
