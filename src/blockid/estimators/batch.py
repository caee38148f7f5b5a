"""Batch (offline) least squares by QR factorisation.

The normal equations square the condition number of the regressor matrix; a QR
factorisation does not. ``partial_fit`` keeps the triangular factor of the augmented
matrix ``[Phi | Y]`` and folds new rows into it (QR updating), so chunks give the same
answer as one solve of the whole record, with memory independent of its length.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, ClassVar

import numpy as np
from scipy.linalg import solve_triangular

from blockid.errors import EstimationError
from blockid.estimators._base import Interval, RegressionEstimator, check_regression

__all__ = ["BatchLeastSquares"]


class BatchLeastSquares(RegressionEstimator):
    """Ordinary (optionally weighted) least squares, ``min_theta sum_t w_t |y_t - Phi_t theta|^2``.

    Parameters
    ----------
    rcond : float, default 1e-10
        A regressor direction whose diagonal entry of ``R`` is below ``rcond`` times the
        largest is treated as unexcited: ``fit`` raises :class:`~blockid.errors.EstimationError`
        naming the column instead of returning arbitrary parameters.

    Attributes
    ----------
    coef_ : ndarray, shape (n,) or (m, n)
        Estimated parameters.
    covariance_ : ndarray, shape (n, n)
        Unscaled covariance ``(Phi^T W Phi)^-1`` (what RLS calls ``P``); multiply by
        ``noise_variance_`` for the parameter covariance.
    noise_variance_ : ndarray, shape (m,)
        Residual variance ``RSS / (N - n)`` per target.
    n_samples_seen_ : int

    Examples
    --------
    >>> import numpy as np
    >>> Phi = np.c_[np.ones(4), np.arange(4.0)]
    >>> BatchLeastSquares().fit(Phi, 1.0 + 2.0 * np.arange(4.0)).coef_.round(12).tolist()
    [1.0, 2.0]
    """

    _parameter_constraints: ClassVar[dict[str, Interval]] = {"rcond": Interval(0.0, 1.0, "right")}

    def __init__(self, *, rcond: float = 1e-10) -> None:
        self.rcond = rcond

    def fit(self, Phi: Any, y: Any, sample_weight: Any = None) -> BatchLeastSquares:
        """Solve the least-squares problem for the whole record."""
        for attr in ("_theta", "_R", "_state_shape"):
            self.__dict__.pop(attr, None)
        return self.partial_fit(Phi, y, sample_weight)

    def fit_chunks(
        self, chunks: Iterable[tuple[Any, Any]], *, normalise: bool = False
    ) -> BatchLeastSquares:
        """Solve the least-squares problem over ``(Phi, y)`` chunks of one record.

        The same answer as :meth:`fit` on the stacked chunks, holding one chunk at a
        time: the factor is folded chunk by chunk and solved once, at the end (so a
        chunk that alone does not excite every column is no error).

        With ``normalise`` the problem is solved on columns scaled to unit RMS (what
        the ``rcond`` test of unexcited directions then compares; powers of a signal
        differ wildly in scale) and the estimate scaled back: ``Q R D = Phi D``, so the
        scaled factor is the data's factor times the scales, and the column RMS are the
        norms of ``R``'s columns over the square root of the rows: one pass over the
        data.
        """
        for attr in ("_theta", "_R", "_state_shape"):
            self.__dict__.pop(attr, None)
        Phi = None
        for Phi, y in chunks:
            Phi = self._fold(Phi, y, None)
        if Phi is None:
            raise EstimationError("least squares needs at least one row of regressors")
        n = self._state_shape[0]
        if self.n_samples_seen_ < n:
            raise EstimationError(
                f"least squares needs at least {n} rows for {n} parameters, got "
                f"{self.n_samples_seen_}"
            )
        if not normalise:
            self._solve(n, Phi)
            return self
        scale = np.linalg.norm(self._R[:, :n], axis=0) / np.sqrt(self.n_samples_seen_)
        scale[scale == 0] = 1.0
        self._R[:, :n] /= scale
        try:
            self._solve(n, Phi)
        finally:
            self._R[:, :n] *= scale  # the factor of the data as given (for partial_fit)
        self._theta = self._theta / scale[:, None]
        self.covariance_ = self.covariance_ / np.outer(scale, scale)
        self._set_coef(self._theta, self._one_d)
        return self

    def partial_fit(self, Phi: Any, y: Any, sample_weight: Any = None) -> BatchLeastSquares:
        """Fold more rows into the factorisation and re-solve."""
        Phi = self._fold(Phi, y, sample_weight)
        if self.n_samples_seen_ >= Phi.shape[1]:  # fewer rows than parameters: wait
            self._solve(Phi.shape[1], Phi)
        return self

    def _fold(self, Phi: Any, y: Any, sample_weight: Any) -> np.ndarray:
        """Fold rows into the triangular factor; returns the checked ``Phi``."""
        self._validate_params()
        Phi, Y, one_d = check_regression(Phi, y)
        n, m = Phi.shape[1], Y.shape[1]
        A = np.hstack([Phi, Y])
        if sample_weight is not None:
            w = np.asarray(sample_weight, dtype=float).reshape(-1)
            if w.shape[0] != A.shape[0] or np.any(w < 0) or not np.all(np.isfinite(w)):
                raise EstimationError(
                    "sample_weight must hold one finite, non-negative weight per row"
                )
            A *= np.sqrt(w)[:, None]
        if self._check_continuation(Phi, Y, one_d):
            A = np.vstack([self._R, A])
            seen = self.n_samples_seen_
        else:
            seen = 0
        R = np.linalg.qr(A, mode="r")
        if R.shape[0] < n + m:  # fewer rows than columns so far: pad to square
            R = np.vstack([R, np.zeros((n + m - R.shape[0], n + m))])
        self._R = R
        self._state_shape = (n, m)
        self._one_d = one_d
        self.n_samples_seen_ = seen + Phi.shape[0]
        return Phi

    def _solve(self, n: int, Phi: np.ndarray) -> None:
        R11, R12, R22 = self._R[:n, :n], self._R[:n, n:], self._R[n:, n:]
        d = np.abs(np.diag(R11))
        scale = d.max() if d.size and d.max() > 0 else 1.0
        weak = np.flatnonzero(d <= self.rcond * scale)
        if weak.size:
            constant = [int(j) for j in weak if np.ptp(Phi[:, j]) == 0.0]
            note = f" (constant over the last rows given: {constant})" if constant else ""
            exc = EstimationError(
                f"least squares is rank deficient: regressor column(s) {weak.tolist()}{note} are "
                f"(nearly) linear combinations of the others over {self.n_samples_seen_} samples; "
                "the data do not excite the model enough, or the orders are too high"
            )
            exc.columns = weak.tolist()  # for callers that can name the columns
            raise exc
        self._theta = solve_triangular(R11, R12)
        Rinv = solve_triangular(R11, np.eye(n))
        self.covariance_ = Rinv @ Rinv.T
        dof = max(self.n_samples_seen_ - n, 1)
        self.noise_variance_ = np.sum(R22**2, axis=0) / dof
        self._set_coef(self._theta, self._one_d)
