"""Shared machinery of the regressor-level estimators (scikit-learn conventions).

Constructors only store their keyword arguments. ``fit`` validates, resets and learns
attributes ending in ``_``; ``partial_fit`` continues from the current state, so a
record fed in chunks gives the same estimates as one ``fit``.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid.errors import DataError, EstimationError, ParameterError

__all__ = ["Interval", "RegressionEstimator", "check_regression"]


class Interval:
    """Allowed range of a numeric parameter, declared next to the class."""

    def __init__(self, lo: float | None, hi: float | None, closed: str = "both") -> None:
        self.lo, self.hi, self.closed = lo, hi, closed

    def __contains__(self, v: float) -> bool:
        if not np.isfinite(v):
            return False
        lo_ok = self.lo is None or (
            v >= self.lo if self.closed in ("both", "left") else v > self.lo
        )
        hi_ok = self.hi is None or (
            v <= self.hi if self.closed in ("both", "right") else v < self.hi
        )
        return lo_ok and hi_ok

    def __str__(self) -> str:
        left = "[" if self.closed in ("both", "left") else "("
        right = "]" if self.closed in ("both", "right") else ")"
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        return f"{left}{lo}, {hi}{right}"


def check_regression(Phi: Any, y: Any) -> tuple[np.ndarray, np.ndarray, bool]:
    """Validate a regression problem; return float64 ``Phi`` (N, n), ``Y`` (N, m), is_1d."""
    Phi = np.asarray(Phi, dtype=float)
    y_arr = np.asarray(y, dtype=float)
    if Phi.ndim != 2:
        raise DataError(f"Phi must be a 2-D array (samples x regressors), got shape {Phi.shape}")
    one_d = y_arr.ndim == 1
    Y = y_arr[:, None] if one_d else y_arr
    if Y.ndim != 2:
        raise DataError(f"y must be 1-D or 2-D (samples x outputs), got shape {y_arr.shape}")
    if Phi.shape[0] != Y.shape[0]:
        raise DataError(
            f"Phi has {Phi.shape[0]} rows but y has {Y.shape[0]}: give one target per regressor row"
        )
    for name, arr in (("Phi", Phi), ("y", Y)):
        bad = ~np.isfinite(arr)
        if bad.any():
            row = int(np.argwhere(bad)[0][0])
            raise DataError(
                f"{name} contains NaN or inf (first at row {row}); remove or fill missing samples"
            )
    return Phi, Y, one_d


class RegressionEstimator:
    """Base class: parameter validation and the ``coef_`` shape convention.

    ``coef_`` has shape (n,) for a 1-D target and (m, n) for m targets, as in
    scikit-learn; internally parameters are kept as an (n, m) array ``_theta``.
    """

    _parameter_constraints: ClassVar[dict[str, Interval]] = {}

    def _validate_params(self) -> None:
        for name, interval in self._parameter_constraints.items():
            value = getattr(self, name)
            if value is None:
                continue
            try:
                ok = float(value) in interval
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ParameterError(
                    f"{type(self).__name__}: {name}={value!r} is outside the allowed "
                    f"range {interval}"
                )

    def get_params(self) -> dict[str, Any]:
        """Constructor arguments, as scikit-learn's ``get_params``."""
        import inspect

        sig = inspect.signature(type(self).__init__)
        return {p: getattr(self, p) for p in sig.parameters if p != "self"}

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"

    def _set_coef(self, theta: np.ndarray, one_d: bool) -> None:
        self.coef_ = theta[:, 0].copy() if one_d else theta.T.copy()

    def _check_continuation(self, Phi: np.ndarray, Y: np.ndarray, one_d: bool) -> bool:
        """True when a previous fit exists and the new chunk is compatible with it."""
        if not hasattr(self, "_state_shape"):
            return False
        n, m = self._state_shape
        if Phi.shape[1] != n or Y.shape[1] != m or one_d != self._one_d:
            raise DataError(
                f"partial_fit got {Phi.shape[1]} regressors and {Y.shape[1]} targets, but the "
                f"estimator was started with {n} and {m}; call fit() to start over"
            )
        return True

    def predict(self, Phi: Any) -> np.ndarray:
        """``Phi @ coef_.T``: the model output for given regressors."""
        if not hasattr(self, "_theta"):
            raise EstimationError(f"{type(self).__name__} is not fitted yet; call fit() first")
        Phi = np.asarray(Phi, dtype=float)
        out = Phi @ self._theta
        return out[:, 0] if self._one_d else out
