"""The base of the online learners (:mod:`blockid.fitting.online`): the
:class:`OnlineEstimator` contract, its state's encoding, and what the learners share
(scales, defaults, orders against a starting model)."""

from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.errors import DataError, EstimationError, ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.fitting.options import OPTIONS
from blockid.fitting.recursive import (
    positive_number,
)

__all__ = ["ONLINE_OPTIONS", "OnlineEstimator", "model_parameters"]

#: Options only online learning takes (not in the registry, not used by offline fits).
ONLINE_OPTIONS = ("initial", "input_scale", "output_scale")

#: Names of the ARX recursions in messages.
_ARX_NAMES = {"rls": "RLS", "aw-rls": "AW-RLS", "hierarchical-rls": "H-RLS"}

#: Options of a finished offline fit that a stream accepts and does not use.
_NOT_USED = ("tol", "convergence_check", "max_mse_ratio", "allow_unstable")


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
    for key in _WHOLE_RECORD[1:]:
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


#: Options of an offline fit whose meaning needs the whole record: refused when set
#: (:func:`_refuse_whole_record`), never read online.
_WHOLE_RECORD = ("passes", "center", "refine", "record_history")


def _defaults(function: Any, opts: dict[str, Any]) -> dict[str, Any]:
    """``opts`` completed with the offline fitter's defaults (one source of truth): a
    value for each of ``function``'s keyword parameters that is a declared option
    (:data:`~blockid.fitting.options.OPTIONS`) online learning can use (not
    :data:`_NOT_USED`, not :data:`_WHOLE_RECORD`). Which of them a learner reads is its
    own business; no learner lists the options it takes a second time."""
    params = inspect.signature(function).parameters
    keys = [
        k
        for k, p in params.items()
        if p.default is not p.empty and k in OPTIONS and k not in _NOT_USED + _WHOLE_RECORD
    ]
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

        >>> from blockid.fitting.online import online_estimator
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
