"""Hierarchical recursive least squares (H-RLS), SPEC (A10).

The regressor is split into groups (paper A: the output lags and the input lags of
each output of the flow field). Each group runs its own smaller RLS with its own
covariance ``P_g``, using the error computed with every group's previous estimate
(the coordination step):

.. math::

    e(t) = y(t) - \\sum_g \\varphi_g^\\top(t)\\hat\\theta_g(t-1),\\qquad
    \\hat\\theta_g(t) = \\hat\\theta_g(t-1) + \\frac{P_g(t-1)\\varphi_g(t)\\, e(t)}
    {\\lambda + \\varphi_g^\\top P_g(t-1)\\varphi_g}

    P_g(t) = \\Bigl[P_g(t-1) - \\frac{P_g(t-1)\\varphi_g\\varphi_g^\\top P_g(t-1)}
    {\\lambda + \\varphi_g^\\top P_g(t-1)\\varphi_g}\\Bigr]/\\lambda

Two groups of size n/2 cost about half of one RLS of size n. The cross-covariance
between groups is ignored, so the estimate is not the least-squares one at every
step. On persistently exciting, noise-free data it converges to the same parameters,
but the rate depends on the forgetting factor: with ``lambda = 1`` the gains decay like
``1/t`` and the coupling error decays only like ``t^-mu`` (mu the smallest eigenvalue of
``blockdiag(R)^-1 R``, about 1 for weakly correlated groups: error 4e-3 after 20 000
samples in the tests), while with ``lambda < 1`` it decays geometrically (1e-10 at
``lambda = 0.999``, 1e-15 at 0.99 on the same data). Use forgetting with H-RLS.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from blockid._kernels import rls as _k
from blockid.defaults import FORGETTING, RECURSIVE
from blockid.errors import ParameterError
from blockid.estimators.forgetting import ForgettingSchedule
from blockid.estimators.rls import RecursiveEstimator

__all__ = ["HierarchicalRLS"]


class HierarchicalRLS(RecursiveEstimator):
    """Hierarchical RLS of paper A (A10) with optional forgetting.

    Parameters
    ----------
    groups : int or sequence of sequences of int, default 2
        How the regressor columns are split. An int ``k`` splits the columns into ``k``
        contiguous, nearly equal groups; otherwise each entry lists the column indices
        of one group (every column exactly once). For the ARX models of blockid,
        :meth:`blockid.models.ARX.hierarchical_groups` gives paper A's split (output lags
        | input lags).
    forgetting, initial_covariance, initial_parameters, max_covariance_trace
        As for :class:`~blockid.estimators.rls.RecursiveLeastSquares` (the trace bound
        is shared among groups in proportion to their size).

    Attributes
    ----------
    coef_ : ndarray, shape (n,) or (m, n)
        In the original column order.
    covariance_ : ndarray, shape (n, n)
        Block-diagonal ``P`` (in the original column order).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> Phi = rng.standard_normal((3000, 4))
    >>> h = HierarchicalRLS(groups=[[0, 2], [1, 3]], forgetting=0.99)
    >>> h = h.fit(Phi, Phi @ [1.0, 2.0, 3.0, 4.0])
    >>> np.allclose(h.coef_, [1.0, 2.0, 3.0, 4.0], atol=1e-6)
    True
    """

    _name = "H-RLS"

    def __init__(
        self,
        *,
        groups: int | Sequence[Sequence[int]] = 2,
        forgetting: float | str | ForgettingSchedule = FORGETTING,
        initial_covariance: float = RECURSIVE["hierarchical-rls"]["initial_covariance"],  # type: ignore[assignment]
        initial_parameters: Any = 0.0,
        max_covariance_trace: float | None = None,
    ) -> None:
        self.groups = groups
        self.forgetting = forgetting
        self.initial_covariance = initial_covariance
        self.initial_parameters = initial_parameters
        self.max_covariance_trace = max_covariance_trace

    def _layout(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Column permutation making groups contiguous, and the group boundaries."""
        if isinstance(self.groups, int | np.integer):
            k = int(self.groups)
            if not 1 <= k <= n:
                raise ParameterError(f"groups={k} must be between 1 and the {n} regressors")
            sizes = [len(c) for c in np.array_split(np.arange(n), k)]
            return np.arange(n), np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        cols = [list(map(int, g)) for g in self.groups]
        flat = sorted(c for g in cols for c in g)
        if flat != list(range(n)) or any(len(g) == 0 for g in cols):
            raise ParameterError(
                f"groups must list every regressor column 0..{n - 1} exactly once, in "
                f"non-empty groups; got {cols}"
            )
        perm = np.array([c for g in cols for c in g])
        bounds = np.concatenate([[0], np.cumsum([len(g) for g in cols])]).astype(np.int64)
        return perm, bounds

    def _initial_state(self, n: int, m: int) -> None:
        super()._initial_state(n, m)
        self._perm, self._bounds = self._layout(n)
        self._inv = np.argsort(self._perm)
        # state kept in the permuted (grouped) order
        self._theta = self._theta[self._perm]

    def _run(self, Phi: np.ndarray, Y: np.ndarray, E: np.ndarray, start: int) -> int:
        # the kernel wants the groups contiguous: work in the permuted column order
        P_orig = self.covariance_
        self.covariance_ = np.ascontiguousarray(P_orig[np.ix_(self._perm, self._perm)])
        status = super()._run(np.ascontiguousarray(Phi[:, self._perm]), Y, E, start)
        self.covariance_ = self.covariance_[np.ix_(self._inv, self._inv)]
        return status

    def _validate_params(self) -> None:
        super()._validate_params()
        # read once per fit/partial_fit call (a schedule instance is used as it is)
        self._schedule = ForgettingSchedule.parse(self.forgetting)

    def _kernel(self, theta, P, Phi, y, e, start) -> int:
        lam = self._schedule.factors(start, Phi.shape[0])
        return _k.hierarchical_rls_run(
            theta, P, Phi, y, self._bounds, lam, self._trace_max(Phi.shape[1]), e
        )

    def _set_coef(self, theta: np.ndarray, one_d: bool) -> None:
        super()._set_coef(theta[self._inv], one_d)

    def predict(self, Phi: Any) -> np.ndarray:
        """``Phi @ coef_.T`` in the original column order."""
        Phi = np.asarray(Phi, dtype=float)
        out = Phi[:, self._perm] @ self._theta
        return out[:, 0] if self._one_d else out
