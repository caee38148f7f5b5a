"""Compiled recursive least-squares kernels.

One update rule serves every recursive estimator in blockid (RLS with forgetting, A2;
adaptive-weighted RLS, A8; the hierarchical RLS of A10; and the internal-variable
algorithms of papers A and B, which build their regressor sample by sample and then
call the same step):

.. math::

    g = P\\varphi,\\quad s = \\varphi^\\top g,\\quad
    \\hat\\theta \\leftarrow \\hat\\theta + g\\,e/(\\rho + s),\\quad
    P \\leftarrow \\bigl(P - g g^\\top/(\\rho + s)\\bigr)/\\lambda

with ``rho = lam`` for ordinary RLS (A2) and ``rho = eps1*s + eps2, lam = 1`` for AW-RLS
(A8). Because :math:`K\\varphi^\\top P = g g^\\top/(\\rho+s)`, the update is written with the
outer product of one vector with itself, with the product ``(g_i g_j)`` formed in an
order-independent way: ``P`` is symmetric *by construction*, to the last bit, unlike the textbook
``P - K phi^T P`` whose rounding errors make ``P`` drift out of symmetry and diverge
after tens of thousands of samples at lambda = 0.99.

Wind-up protection: with lambda < 1 and no excitation, ``P`` grows like ``lambda^-t``.
After every update the trace of ``P`` is bounded by ``trace_max``; when it would exceed
it, ``P`` is scaled down to that trace (a uniform rescale keeps ``P`` symmetric positive
definite). A non-finite or non-positive-definite step stops the run and reports the
sample index, so callers can raise a clear error instead of returning garbage.

Kernels depend on NumPy only. Every kernel has a plain-NumPy twin in the tests.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "gain",
    "prior_error",
    "covariance_update",
    "apply_update",
    "bound_trace",
    "rls_run",
    "aw_rls_run",
    "hierarchical_rls_run",
    "OK",
]

#: Status value returned by the ``*_run`` kernels when every sample was processed.
OK = -1


@njit(cache=True)
def gain(P, phi, g):
    """``g = P phi`` for symmetric ``P``; returns ``s = phi^T P phi``.

    Accumulates rows of ``P`` (equal to its columns) so that the inner loop runs over
    independent entries of ``g`` and vectorises without reassociating sums.
    """
    n = phi.shape[0]
    for i in range(n):
        g[i] = 0.0
    for j in range(n):
        pj = phi[j]
        for i in range(n):
            g[i] += P[j, i] * pj
    s = 0.0
    for i in range(n):
        s += phi[i] * g[i]
    return s


@njit(cache=True)
def prior_error(theta, phi, y, err):
    """A-priori errors ``err = y - theta^T phi`` for m outputs sharing ``phi``."""
    n = phi.shape[0]
    for k in range(y.shape[0]):
        pred = 0.0
        for i in range(n):
            pred += phi[i] * theta[i, k]
        err[k] = y[k] - pred


@njit(cache=True)
def covariance_update(P, g, inv_d, inv_lam):
    """``P <- (P - g g^T inv_d) * inv_lam``, keeping ``P`` exactly symmetric.

    ``(g[i] * g[j]) * inv_d`` is bitwise equal to ``(g[j] * g[i]) * inv_d``, so a
    symmetric ``P`` stays symmetric to the last bit while the loop vectorises.
    Returns False when a diagonal entry is no longer positive and finite.
    """
    n = g.shape[0]
    for i in range(n):
        gi = g[i]
        for j in range(n):
            P[i, j] = (P[i, j] - (gi * g[j]) * inv_d) * inv_lam
    ok = True
    for i in range(n):
        if not (P[i, i] > 0.0) or not np.isfinite(P[i, i]):
            ok = False
    return ok


@njit(cache=True)
def apply_update(theta, P, phi, y, g, denom, inv_lam, err):
    """Apply one RLS step given ``g = P phi`` and ``denom = rho + s``.

    ``theta`` is (n, m) for m outputs sharing the regressor ``phi``; ``y`` has length m.
    The a-priori errors are written to ``err``. Returns False when the step is not
    finite or ``P`` lost positive diagonal entries.
    """
    if not (denom > 0.0) or not np.isfinite(denom):
        return False
    prior_error(theta, phi, y, err)  # e = y - phi^T theta(t-1)      (A2, A8, B5)
    inv_d = 1.0 / denom
    for k in range(y.shape[0]):  # theta(t) = theta(t-1) + P phi e / (rho + s)
        ek = err[k] * inv_d
        for i in range(phi.shape[0]):
            theta[i, k] += g[i] * ek
    return covariance_update(P, g, inv_d, inv_lam)  # P(t) = (P - g g^T/(rho+s))/lam


@njit(cache=True)
def bound_trace(P, trace_max):
    """Scale ``P`` down so that ``trace(P) <= trace_max`` (anti-wind-up)."""
    n = P.shape[0]
    tr = 0.0
    for i in range(n):
        tr += P[i, i]
    if tr > trace_max:
        c = trace_max / tr
        for i in range(n):
            for j in range(n):
                P[i, j] *= c
        return True
    return False


@njit(cache=True)
def rls_run(theta, P, Phi, Y, lam, trace_max, E):
    """Exponentially weighted RLS (A2) over the rows of ``Phi``/``Y`` in place.

    ``lam[t]`` is the forgetting factor of sample t. A-priori errors go to ``E``.
    Returns ``OK`` or the index of the first sample whose update failed.
    """
    N, n = Phi.shape
    g = np.empty(n)
    for t in range(N):
        phi = Phi[t]
        s = gain(P, phi, g)
        if not apply_update(theta, P, phi, Y[t], g, lam[t] + s, 1.0 / lam[t], E[t]):
            return t
        if lam[t] < 1.0:
            bound_trace(P, trace_max)
    return OK


@njit(cache=True)
def aw_rls_run(theta, P, Phi, Y, eps1, eps2, W, E):
    """Adaptive-weighted RLS (A8) in place; ``W[t]`` receives the weight lambda(t)."""
    N, n = Phi.shape
    g = np.empty(n)
    for t in range(N):
        phi = Phi[t]
        s = gain(P, phi, g)
        rho = eps1 * s + eps2  # lambda(t) = eps1 s(t) + eps2        (A8)
        W[t] = rho
        if not apply_update(theta, P, phi, Y[t], g, rho + s, 1.0, E[t]):
            return t
    return OK


@njit(cache=True)
def hierarchical_rls_run(theta, P, Phi, Y, bounds, lam, trace_max, E):
    """Hierarchical RLS (A10) over contiguous parameter groups, in place.

    ``bounds`` holds group boundaries ``[0, n1, n1 + n2, ..., n]``. Every group uses the
    error computed with *all* groups' previous estimates (the coordination step) and
    updates only its own diagonal block of ``P``.
    """
    N, n = Phi.shape
    m = Y.shape[1]
    n_groups = bounds.shape[0] - 1
    g = np.empty(n)
    e = np.empty(m)
    for t in range(N):
        phi = Phi[t]
        prior_error(theta, phi, Y[t], e)  # common error with every theta(t-1)   (A10)
        E[t] = e
        inv_lam = 1.0 / lam[t]
        for grp in range(n_groups):
            a = bounds[grp]
            b = bounds[grp + 1]
            Pg = P[a:b, a:b]
            gg = g[a:b]
            s = gain(Pg, phi[a:b], gg)
            denom = lam[t] + s
            if not (denom > 0.0) or not np.isfinite(denom):
                return t
            inv_d = 1.0 / denom
            for k in range(m):  # theta_g(t) = theta_g(t-1) + P_g(t) phi_g e
                ek = e[k] * inv_d
                for i in range(a, b):
                    theta[i, k] += g[i] * ek
            if not covariance_update(Pg, gg, inv_d, inv_lam):
                return t
            if lam[t] < 1.0:
                bound_trace(Pg, trace_max * (b - a) / n)
    return OK
