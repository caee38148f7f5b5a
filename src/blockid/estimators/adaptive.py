"""Adaptive-weighted recursive least squares (AW-RLS), SPEC (A8).

.. math::

    s(t) = \\varphi^\\top(t) P(t-1) \\varphi(t),

    \\lambda(t) = \\varepsilon_1 s(t) + \\varepsilon_2

    \\hat\\theta(t) = \\hat\\theta(t-1) + \\frac{P(t-1)\\varphi(t) e(t)}{\\lambda(t) + s(t)},\\qquad
    P(t) = P(t-1) - \\frac{P(t-1)\\varphi\\varphi^\\top P(t-1)}{\\lambda(t) + s(t)}

This is RLS in which sample t carries the weight ``1/lambda(t)``: while ``P`` is large
(early, or after a bad start) the weight is small and one sample cannot throw the
estimate far; as ``P`` shrinks the ``eps1`` term vanishes and the weight tends to
``1/eps2``. After N samples the estimate is exactly the weighted least-squares solution
with weights ``1/lambda(t)`` (regularised by ``P(0)``); the weights are kept in
``weights_`` so that this can be checked. ``P`` only shrinks, so there is no wind-up.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from blockid._kernels import rls as _k
from blockid.defaults import RECURSIVE
from blockid.estimators._base import Interval
from blockid.estimators.rls import RecursiveEstimator

__all__ = ["AdaptiveWeightedRLS"]


class AdaptiveWeightedRLS(RecursiveEstimator):
    """Adaptive-weighted RLS of paper A (A8).

    Parameters
    ----------
    eps1 : float, default 1.0
        Weight of ``s(t)`` in ``lambda(t)``; large values help from bad initial values.
    eps2 : float, default 0.1
        Floor of ``lambda(t)``; small values keep convergence fast.
    initial_covariance : float, default 1e5
        ``P(0)`` (paper A: 1e5).
    initial_parameters : float or array, default 0.01
        ``theta(0)`` (paper A: 1e-2 in every entry).

    Attributes
    ----------
    coef_, covariance_, prediction_errors_, n_samples_seen_
        As for :class:`~blockid.estimators.rls.RecursiveLeastSquares`.
    weights_ : ndarray
        ``lambda(t)`` of the samples of the last call; sample t's least-squares weight
        is ``1 / lambda(t)``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> Phi = rng.standard_normal((2000, 2))
    >>> aw = AdaptiveWeightedRLS().fit(Phi, Phi @ [0.9, 0.72])
    >>> np.allclose(aw.coef_, [0.9, 0.72], atol=1e-6)
    True
    """

    _parameter_constraints: ClassVar[dict[str, Interval]] = {
        **RecursiveEstimator._parameter_constraints,
        "eps1": Interval(0.0, None, "left"),
        "eps2": Interval(0.0, None, "neither"),
    }
    _name = "AW-RLS"

    def __init__(
        self,
        *,
        eps1: float = RECURSIVE["aw-rls"]["eps1"],  # type: ignore[assignment]
        eps2: float = RECURSIVE["aw-rls"]["eps2"],  # type: ignore[assignment]
        initial_covariance: float = RECURSIVE["aw-rls"]["initial_covariance"],  # type: ignore[assignment]
        initial_parameters: Any = 0.01,
    ) -> None:
        self.eps1 = eps1
        self.eps2 = eps2
        self.initial_covariance = initial_covariance
        self.initial_parameters = initial_parameters

    max_covariance_trace = None  # P never grows in AW-RLS

    def _kernel(self, theta, P, Phi, y, e, start) -> int:
        W = np.empty(Phi.shape[0])
        status = _k.aw_rls_run(theta, P, Phi, y, float(self.eps1), float(self.eps2), W, e)
        self.weights_ = W  # the same for every target: it depends on P and phi only
        return status
