"""Compiled recursive least-squares kernels.

One update rule, :func:`rls_step`, serves every recursive estimator in blockid (RLS
with forgetting, A2; adaptive-weighted RLS, A8; and the internal-variable algorithms of
papers A and B, which build their regressor sample by sample and then call the same
step). With ``g = P phi`` and ``s = phi^T g``:

.. math::

    e = y - \\varphi^\\top\\hat\\theta,\\quad d = \\rho_0 + c\\,s,\\quad
    \\hat\\theta \\leftarrow \\hat\\theta + g\\,e/d,\\quad
    P \\leftarrow \\bigl(P - g g^\\top/d\\bigr)/\\lambda

RLS (A2) is ``rho0 = lambda, c = 1``; AW-RLS (A8) is ``rho0 = eps2, c = 1 + eps1,
lambda = 1`` (its weight ``lambda(t) = eps1 s + eps2``, so ``d = lambda(t) + s``).

Numerical form. Because :math:`K\\varphi^\\top P = g g^\\top/d`, the covariance update is
written with the outer product of one vector with itself, formed as ``(g_i g_j) / d``,
which is bitwise symmetric in i and j: ``P`` stays exactly symmetric, unlike the
textbook ``P - K phi^T P`` whose rounding makes ``P`` drift out of symmetry and diverge
after tens of thousands of samples at lambda = 0.99. ``g = P phi`` accumulates rows of
``P`` (equal to its columns) so the inner loops vectorise.

Wind-up protection. With lambda < 1 and no excitation, ``P`` grows like lambda^-t. After
every step the trace of ``P`` is bounded by ``trace_max``; when it would exceed it, ``P``
is scaled down to that trace (a uniform rescale keeps it symmetric positive definite).

Failure. A non-finite or non-positive step returns False and leaves the sample index to
the caller, so estimators raise a clear error instead of returning garbage.

Kernels are single-output (the common case, and the fastest); estimators loop over
targets. Every kernel has a plain-NumPy twin in the tests.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["OK", "recorded_step", "rls_step", "rls_run", "aw_rls_run", "hierarchical_rls_run"]

#: Status value returned by the ``*_run`` kernels when every sample was processed.
OK = -1


@njit(cache=True)
def rls_step(theta, P, phi, y, g, rho0, s_coef, inv_lam, trace_max, out):
    """One fused RLS step in place; ``out[0] = e`` (a-priori error), ``out[1] = s``.

    Returns False (leaving ``theta``/``P`` possibly modified) when the step is not
    finite or ``P`` lost positive definiteness.
    """
    n = phi.shape[0]
    for i in range(n):  # g = P phi
        g[i] = 0.0
    for j in range(n):
        pj = phi[j]
        for i in range(n):
            g[i] += P[j, i] * pj
    s = 0.0
    pred = 0.0
    for i in range(n):  # s = phi^T P phi,  y_hat = phi^T theta(t-1)
        s += phi[i] * g[i]
        pred += phi[i] * theta[i]
    d = rho0 + s_coef * s  # lambda + s (A2)  or  lambda(t) + s (A8)
    if not (d > 0.0) or not np.isfinite(d):
        return False
    e = y - pred
    out[0] = e
    out[1] = s
    inv_d = 1.0 / d
    ek = e * inv_d
    tr = 0.0
    for i in range(n):
        gi = g[i]
        theta[i] += gi * ek  # theta(t) = theta(t-1) + P phi e / d
        for j in range(n):  # P(t) = (P - g g^T / d) / lambda, bitwise symmetric
            P[i, j] = (P[i, j] - (gi * g[j]) * inv_d) * inv_lam
        tr += P[i, i]
        if not (P[i, i] > 0.0):
            return False
    if not np.isfinite(tr):
        return False
    if tr > trace_max:  # anti-wind-up: bound trace(P)
        c = trace_max / tr
        for i in range(n):
            for j in range(n):
                P[i, j] *= c
    return True


@njit(cache=True)
def recorded_step(ok, theta, out, err, hist, k, n0, stride, row):
    """The bookkeeping after :func:`rls_step` at sample ``k`` of a recursion over a record
    (the key-term and backlash kernels): the a-priori error ``out[0]`` into ``err[k]``
    (if given), ``theta`` into ``hist`` every ``stride``-th update from ``n0``. Returns
    the next history row, or -1 when the step failed (``ok`` False or a non-finite
    error)."""
    if not ok or not np.isfinite(out[0]):
        return -1
    if err is not None:
        err[k] = out[0]
    if row < hist.shape[0] and (k - n0 + 1) % stride == 0:
        for i in range(theta.shape[0]):
            hist[row, i] = theta[i]
        row += 1
    return row


@njit(cache=True)
def rls_run(theta, P, Phi, y, lam, trace_max, E):
    """Exponentially weighted RLS (A2) over the rows of ``Phi`` / entries of ``y``.

    ``lam[t]`` is the forgetting factor of sample t; the trace bound applies only to
    samples with ``lam[t] < 1``. A-priori errors go to ``E``. Returns ``OK`` or the
    index of the first sample whose update failed.
    """
    N, n = Phi.shape
    g = np.empty(n)
    phi = np.empty(n)
    out = np.empty(2)
    for t in range(N):
        for i in range(n):
            phi[i] = Phi[t, i]
        bound = trace_max if lam[t] < 1.0 else np.inf
        if not rls_step(theta, P, phi, y[t], g, lam[t], 1.0, 1.0 / lam[t], bound, out):
            return t
        E[t] = out[0]
    return OK


@njit(cache=True)
def aw_rls_run(theta, P, Phi, y, eps1, eps2, W, E):
    """Adaptive-weighted RLS (A8) in place; ``W[t]`` receives the weight lambda(t)."""
    N, n = Phi.shape
    g = np.empty(n)
    phi = np.empty(n)
    out = np.empty(2)
    for t in range(N):
        for i in range(n):
            phi[i] = Phi[t, i]
        # d = lambda(t) + s with lambda(t) = eps1 s + eps2                 (A8)
        if not rls_step(theta, P, phi, y[t], g, eps2, 1.0 + eps1, 1.0, np.inf, out):
            return t
        W[t] = eps1 * out[1] + eps2
        E[t] = out[0]
    return OK


@njit(cache=True)
def hierarchical_rls_run(theta, P, Phi, y, bounds, lam, trace_max, E):
    """Hierarchical RLS (A10) over contiguous parameter groups, in place.

    ``bounds`` holds group boundaries ``[0, n1, n1 + n2, ..., n]``. Every group uses the
    error computed with *all* groups' previous estimates (the coordination step) and
    updates only its own diagonal block of ``P``; its trace bound is ``trace_max``
    shared in proportion to the group size.
    """
    N, n = Phi.shape
    n_groups = bounds.shape[0] - 1
    g = np.empty(n)
    phi = np.empty(n)
    out = np.empty(2)
    for t in range(N):
        e = y[t]
        for i in range(n):  # common error with every theta_g(t-1)           (A10)
            phi[i] = Phi[t, i]
            e -= phi[i] * theta[i]
        E[t] = e
        for grp in range(n_groups):
            a = bounds[grp]
            b = bounds[grp + 1]
            # a group step is an RLS step on its own block with the common error as
            # target: y_g = e + phi_g^T theta_g(t-1) gives e_g = e
            yg = e
            for i in range(a, b):
                yg += phi[i] * theta[i]
            bound = trace_max * (b - a) / n if lam[t] < 1.0 else np.inf
            ok = rls_step(
                theta[a:b],
                P[a:b, a:b],
                phi[a:b],
                yg,
                g[a:b],
                lam[t],
                1.0,
                1.0 / lam[t],
                bound,
                out,
            )
            if not ok:
                return t
    return OK
