"""AW-RLS for the backlash model with internal-variable estimation: paper A (A6–A8).

One pass over one experiment. With the key term ``b_0 x(t - nk)`` (``b_0 = 1``, the
paper's ``b_1``) replaced by the backlash equation (A4), the model is linear in

.. math::

    \\theta = [m_L,\\ m_L c_L,\\ m_R,\\ m_R c_R,\\ b_1..b_{nb-1},\\ a_1..a_{na}]

(A6, MATLAB orders: the paper's ``mf = nb``, ``nf = na``, and its model is ``nk = 1``):

.. math::

    v(t) - \\hat x(t-n_k-1)[1-\\hat f_1(t-n_k)][1-\\hat f_2(t-n_k)] = \\hat\\varphi^\\top(t)\\theta

    \\hat\\varphi(t) = [u \\hat f_1,\\ \\hat f_1,\\ u \\hat f_2,\\ -\\hat f_2
        \\ (\\text{at } t-n_k),\\ \\hat x(t-n_k-1)..\\hat x(t-n_k-nb+1),\\ -v(t-1)..-v(t-na)]

Per sample: build :math:`\\hat\\varphi(t)` and the target from stored past internal
variables, take one AW-RLS step (A8) through :func:`blockid._kernels.rls.rls_step`
(``rho0 = eps2, s_coef = 1 + eps1``: ``d = lambda(t) + s`` with ``lambda(t) = eps1 s +
eps2``), then estimate ``f1(t), f2(t), x(t)`` with the *newest* estimate (A7): the
switching values by :func:`blockid._kernels.backlash.backlash_step` with ``m_L =
theta_1, c_L = theta_2/theta_1, m_R = theta_3, c_R = theta_4/theta_3`` (its
``h(u - z_L)`` is (A7)'s ``h([m_L u + m_L c_L - x]/m_L)``), and ``x`` by (A4) with
those switching values, as the paper does. Where a wrong estimate makes the branch
lines cross (``z_L > z_R``) both switching values can be 1 and (A4) adds both
branches; that is the paper's algorithm, kept as is.

Before the first sample the backlash is at rest in the middle of its estimated dead
band at the first input (the convention of
:meth:`blockid.models.BacklashModel.simulate`; paper A does not say; see
:func:`backlash_rest`); parameters are updated from sample ``n0 = max_lag`` on.

Continuation (online learning, :mod:`blockid.fitting.online`): with a sixth entry
``start`` in ``orders``, samples ``t < start`` are history: their ``u, v, x, f1, f2``
are used as given and nothing is computed or updated for them. The history must reach
back as far as the pass does, ``start >= max(n0, nk + 1)`` (before the record: ``x``
at rest, :func:`backlash_rest`); a pass split into chunks so gives the result of one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from blockid._kernels.backlash import backlash_step
from blockid._kernels.rls import OK, recorded_step, rls_step

__all__ = [
    "OK",
    "REASON_OK",
    "REASON_STEP",
    "REASON_EXPLODED",
    "REASON_ZERO_SLOPE",
    "backlash_aw_rls_run",
    "backlash_rest",
]

REASON_OK = 0
REASON_STEP = 1  # the AW-RLS step (or its error) was not finite, or P lost definiteness
REASON_EXPLODED = 2  # |x_hat| exceeded the limit
REASON_ZERO_SLOPE = 3  # theta_1 or theta_3 is 0: the dead-band edges of (A7) are undefined


@njit(cache=True)
def backlash_rest(theta, u0):
    """``x(-1)``: the backlash of estimate ``theta`` at rest in the middle of its dead band
    at input ``u0`` (the convention of BacklashModel.simulate),
    ``(mL (u0 + cL) + mR (u0 - cR)) / 2``."""
    return 0.5 * (theta[0] * u0 + theta[1] + theta[2] * u0 - theta[3])


@njit(cache=True)
def backlash_aw_rls_run(theta, P, u, v, orders, params, x, f1, f2, hist, err=None):
    """One pass of AW-RLS (A6–A8) over one experiment, in place.

    Parameters
    ----------
    theta, P : ndarray
        Estimate and covariance, updated in place.
    u, v : ndarray, shape (N,)
        Backlash input and measured output of the linear block.
    orders : ndarray of int64
        ``[nb, na, nk, n0, hist_stride]``, optionally followed by ``start`` (default 0):
        samples before it are history, used as given (module docstring).
    params : ndarray of float
        ``[eps1, eps2, x_limit]``.
    x, f1, f2 : ndarray, shape (N,)
        Receive the internal variables ``x_hat``, ``f1_hat``, ``f2_hat``.
    hist : ndarray, shape (M, n)
        Receives ``theta`` after every ``hist_stride``-th update (M may be 0).
    err : ndarray, shape (N,), optional
        Receives the a-priori error of (A8), ``target(t) - phi_hat(t)^T theta(t-1)``, of
        every updated sample (other entries untouched).

    Returns
    -------
    status : int
        ``OK`` or the index of the sample at which the pass failed.
    reason : int
        One of the ``REASON_*`` values.
    """
    nb, na, nk, n0, stride = orders[0], orders[1], orders[2], orders[3], orders[4]
    eps1, eps2, x_limit = params[0], params[1], params[2]
    start = orders[5] if orders.shape[0] > 5 else 0
    N = u.shape[0]
    n = theta.shape[0]
    phi = np.empty(n)
    g = np.empty(n)
    out = np.empty(2)
    row = 0
    # the backlash starts at rest in the middle of its (estimated) dead band at u(0)
    x_rest = backlash_rest(theta, u[0]) if N > 0 else 0.0
    for t in range(start, N):
        if t >= n0:
            d = t - nk  # the key term's sample
            x_before = x[d - 1] if d >= 1 else x_rest
            phi[0] = u[d] * f1[d]  # (A6)
            phi[1] = f1[d]
            phi[2] = u[d] * f2[d]
            phi[3] = -f2[d]
            for i in range(1, nb):
                j = d - i
                phi[3 + i] = x[j] if j >= 0 else x_rest
            for j in range(1, na + 1):
                phi[3 + nb + j - 1] = -v[t - j]
            target = v[t] - x_before * (1.0 - f1[d]) * (1.0 - f2[d])  # (A6)
            # AW-RLS (A8): d = lambda(t) + s, lambda(t) = eps1 s + eps2
            ok = rls_step(theta, P, phi, target, g, eps2, 1.0 + eps1, 1.0, np.inf, out)
            row = recorded_step(ok, theta, out, err, hist, t, n0, stride, row)
            if row < 0:
                return t, REASON_STEP
        # internal variables with the newest estimates                      (A7)
        m_left, m_right = theta[0], theta[2]
        if m_left == 0.0 or m_right == 0.0:
            return t, REASON_ZERO_SLOPE
        x_prev = x[t - 1] if t >= 1 else x_rest
        _, s1, s2 = backlash_step(
            u[t], x_prev, m_left, theta[1] / m_left, m_right, theta[3] / m_right
        )
        f1[t] = s1
        f2[t] = s2
        ut = u[t]
        xt = (  # (A4) with the estimated switching values                 (A7)
            m_left * ut * s1
            + theta[1] * s1
            + m_right * ut * s2
            - theta[3] * s2
            + x_prev * (1.0 - s1) * (1.0 - s2)
        )
        if not (abs(xt) <= x_limit):
            return t, REASON_EXPLODED
        x[t] = xt
    return OK, REASON_OK
