"""Recursive least squares with a forgetting factor or schedule (SPEC A2, B5).

.. math::

    e(t) = y(t) - \\varphi^\\top(t)\\hat\\theta(t-1),\\quad
    K(t) = \\frac{P(t-1)\\varphi(t)}{\\lambda(t) + \\varphi^\\top(t) P(t-1)\\varphi(t)}

    \\hat\\theta(t) = \\hat\\theta(t-1) + K(t) e(t),\\quad
    P(t) = \\bigl[P(t-1) - K(t)\\varphi^\\top(t) P(t-1)\\bigr]/\\lambda(t)

With ``lambda = 1`` and ``P(0) = mu I`` the estimate after N samples is the
least-squares solution regularised by ``|theta - theta(0)|^2 / mu``; with a large
``mu`` (default 1e8) it equals batch least squares to rounding. With ``lambda < 1`` it
is the exponentially weighted least-squares solution. The covariance update is done in
a symmetric form and its trace is bounded (anti-wind-up), see
:mod:`blockid._kernels.rls`.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid._kernels import rls as _k
from blockid._kernels import writable
from blockid.defaults import FORGETTING, RECURSIVE
from blockid.errors import EstimationError, ParameterError
from blockid.estimators._base import Interval, RegressionEstimator, check_regression
from blockid.estimators.forgetting import ForgettingSchedule

__all__ = ["RecursiveEstimator", "RecursiveLeastSquares"]


class RecursiveEstimator(RegressionEstimator):
    """Common state handling of the recursive estimators.

    Subclasses implement ``_kernel(theta, P, Phi, y, e, start) -> status`` for one
    target; :meth:`_run` applies it to every target. ``P`` evolves independently of the
    targets, so every target starts from the same ``P`` and the one kept is identical
    for all of them.
    """

    _parameter_constraints: ClassVar[dict[str, Interval]] = {
        "initial_covariance": Interval(0.0, None, "neither"),
        "max_covariance_trace": Interval(0.0, None, "neither"),
    }
    _name: ClassVar[str] = "RLS"

    def _initial_state(self, n: int, m: int) -> None:
        theta0 = np.asarray(self.initial_parameters, dtype=float)
        if theta0.ndim == 0:
            theta = np.full((n, m), float(theta0))
        elif theta0.shape in ((n,), (n, 1)) and m == 1:
            theta = theta0.reshape(n, 1).copy()
        elif theta0.shape == (m, n):
            theta = theta0.T.copy()
        else:
            raise ParameterError(
                f"initial_parameters has shape {theta0.shape}; expected a scalar or "
                f"{(n,) if m == 1 else (m, n)} for {n} regressors and {m} targets"
            )
        self._theta = theta
        self._state_shape = (n, m)
        self.covariance_ = float(self.initial_covariance) * np.eye(n)
        self.n_samples_seen_ = 0

    def _trace_max(self, n: int) -> float:
        if self.max_covariance_trace is not None:
            return float(self.max_covariance_trace)
        return float(self.initial_covariance) * n

    def fit(self, Phi: Any, y: Any) -> RecursiveEstimator:
        """Run the recursion over the whole record from the initial state."""
        for attr in ("_theta", "covariance_", "_state_shape"):
            self.__dict__.pop(attr, None)
        return self.partial_fit(Phi, y)

    def partial_fit(self, Phi: Any, y: Any) -> RecursiveEstimator:
        """Continue the recursion over more samples (sample by sample or in chunks)."""
        self._validate_params()
        Phi, Y, one_d = check_regression(Phi, y)
        if not self._check_continuation(Phi, Y, one_d):
            self._initial_state(Phi.shape[1], Y.shape[1])
        self._one_d = one_d
        Phi = np.ascontiguousarray(Phi)
        Y = np.ascontiguousarray(Y)
        E = np.empty_like(Y)
        start = self.n_samples_seen_
        theta_before = self._theta.copy()
        P_before = self.covariance_.copy()
        status = self._run(Phi, Y, E, start)
        if status != _k.OK:
            self._theta, self.covariance_ = theta_before, P_before
            raise EstimationError(
                f"{self._name} diverged at sample {start + status}: the covariance or the "
                "estimate became non-finite or lost positive definiteness. Scale the signals "
                "to order one, lower initial_covariance, or check the data for outliers; the "
                "estimator state was left as it was before this call"
            )
        if not np.all(np.isfinite(self._theta)):
            self._theta, self.covariance_ = theta_before, P_before
            raise EstimationError(f"{self._name} produced non-finite parameter estimates")
        self.prediction_errors_ = E[:, 0] if one_d else E
        self.n_samples_seen_ = start + Phi.shape[0]
        self._set_coef(self._theta, one_d)
        return self

    def _run(self, Phi: np.ndarray, Y: np.ndarray, E: np.ndarray, start: int) -> int:
        P0 = self.covariance_
        status = _k.OK
        Phi = writable(Phi)  # read-only regressors would compile the kernels again
        for k in range(Y.shape[1]):
            P = P0.copy() if k < Y.shape[1] - 1 else P0
            theta = np.ascontiguousarray(self._theta[:, k])
            e = np.empty(Y.shape[0])
            st = self._kernel(theta, P, Phi, writable(Y[:, k]), e, start)
            self._theta[:, k] = theta
            E[:, k] = e
            if st != _k.OK:
                status = st if status == _k.OK else min(status, st)
            if k == 0:
                P_kept = P
        self.covariance_ = P_kept
        return status


class RecursiveLeastSquares(RecursiveEstimator):
    """Recursive least squares (A2) with constant or scheduled forgetting.

    Parameters
    ----------
    forgetting : float or str or ForgettingSchedule, default 1.0
        Constant factor in (0, 1] or a schedule such as ``"0.98:200,1"`` (paper B),
        read at the start of every ``fit``/``partial_fit`` call; a schedule counts the
        samples seen since the last ``fit``.
    initial_covariance : float, default 1e8
        ``P(0) = initial_covariance * I``.
    initial_parameters : float or array, default 0.0
        ``theta(0)``; a scalar fills every entry (the papers use a small epsilon).
    max_covariance_trace : float, optional
        Anti-wind-up bound on ``trace(P)`` applied after every step with
        ``lambda < 1``. Default ``n * initial_covariance``: ``P`` never grows beyond its
        initial uncertainty when excitation is lost.

    Attributes
    ----------
    coef_ : ndarray, shape (n,) or (m, n)
    covariance_ : ndarray, shape (n, n)
        The matrix ``P`` (unscaled covariance).
    prediction_errors_ : ndarray
        A-priori errors ``e(t)`` of the last ``fit``/``partial_fit`` call.
    n_samples_seen_ : int

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> Phi = rng.standard_normal((500, 3))
    >>> rls = RecursiveLeastSquares().fit(Phi, Phi @ [1.0, -2.0, 0.5])
    >>> np.allclose(rls.coef_, [1.0, -2.0, 0.5])
    True
    """

    _name = "RLS"

    def __init__(
        self,
        *,
        forgetting: float | str | ForgettingSchedule = FORGETTING,
        initial_covariance: float = RECURSIVE["rls"]["initial_covariance"],  # type: ignore[assignment]
        initial_parameters: Any = 0.0,
        max_covariance_trace: float | None = None,
    ) -> None:
        self.forgetting = forgetting
        self.initial_covariance = initial_covariance
        self.initial_parameters = initial_parameters
        self.max_covariance_trace = max_covariance_trace

    def _validate_params(self) -> None:
        super()._validate_params()
        # read once per fit/partial_fit call (a schedule instance is used as it is)
        self._schedule = ForgettingSchedule.parse(self.forgetting)

    def _kernel(self, theta, P, Phi, y, e, start) -> int:
        lam = self._schedule.factors(start, Phi.shape[0])
        return _k.rls_run(theta, P, Phi, y, lam, self._trace_max(Phi.shape[1]), e)
