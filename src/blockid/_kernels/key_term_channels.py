"""Key-term RLS of several input channels: paper B's recursion (B4, B5) for a model
with one static block per input and one output.

The model (one output, inputs ``c = 1..m``, each with its own delay ``nk_c``):

.. math::

    w_c(k) = [c = 1]\\, \\gamma_0 + \\sum_j \\gamma_{c,j}\\, \\varphi_{c,j}(k)

    x(k) = \\sum_c \\sum_{i=0}^{n_b-1} b_{c,i}\\, w_c(k-n_{k,c}-i)
           - \\sum_{j=1}^{n_a} a_j\\, x(k-j), \\qquad
    y(k) = x(k) + \\sum_{m\\ge 2} q_m x^m(k)

where ``phi_c`` are the basis functions of channel ``c``'s block evaluated by the
caller (any block linear in its parameters: the powers of a polynomial, the powers and
switched powers of paper B's two-segment polynomial; constant functions excluded, the
one constant ``gamma_0`` rides on the first channel, since a constant on every channel
would give equal regressor columns). Key-term separation fixes every ``b_{c,0} = 1``
and ``q_1 = 1`` and makes ``y(k)`` linear in the parameters once ``w`` and ``x`` are
known; the recursion replaces them by estimates from the newest parameters, sample by
sample, as :mod:`blockid._kernels.key_term` does for one input.

Without input blocks (``has_in = 0``) ``phi_c`` is the input itself (one function),
``w_c = phi_c`` and every ``b_{c,0}`` is free, and with an output block the model may
carry an output bias ``h`` (``bias``: ``y = h + x + ..``, ``h`` first in ``theta``);
without an output block (``has_out = 0``) ``x = y`` is measured.

Parameter vector: ``[gamma_0, gamma_1 (nf), .., gamma_m (nf), b_1 (nb - 1), ..,
b_m (nb - 1), a_1..a_na, q_2..q_r2]`` with input blocks, ``[b_1 (nb), .., b_m (nb),
a, q]`` without. With one channel and paper B's two-segment basis this is exactly the
single-input layout of (B4).

Values before the start of the record are 0; the parameters are updated from sample
``n0`` on. ``start`` (``orders[7]``) marks the samples before it as history, used as
given, so a pass can be split into chunks (see the single-input kernel).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from blockid._kernels.key_term import REASON_EXPLODED, REASON_OK, REASON_STEP, minus_ar, output_step
from blockid._kernels.rls import OK

__all__ = ["OK", "REASON_EXPLODED", "REASON_OK", "REASON_STEP", "key_term_channels_run"]


@njit(cache=True)
def key_term_channels_run(theta, P, phi_u, y, lam, orders, delays, limits, w, x, hist, err):
    """One pass of key-term RLS over one experiment of several inputs, in place.

    Parameters
    ----------
    theta, P : ndarray
        Estimate and covariance, updated in place (layout: module docstring).
    phi_u : ndarray, shape (N, m, nf)
        The basis functions of every channel at every sample (the input itself,
        ``nf = 1``, without input blocks).
    y : ndarray, shape (N,)
        Measured output.
    lam : ndarray, shape (N,)
        Forgetting factor of every sample (entries before ``n0`` are not used).
    orders : ndarray of int64
        ``[nb, na, r2, has_in, has_out, n0, hist_stride, start, bias]``; ``bias``:
        without input blocks, an output bias ``h`` first in ``theta`` (``y = h + x +
        Σ q_m x^m``; a constant in neither ``w`` nor ``x``).
    delays : ndarray of int64, shape (m,)
        ``nk_c`` of every channel.
    limits : ndarray of float
        ``[trace_max, x_limit]``: trace bound of ``P`` while ``lam < 1``, and the bound
        on ``|x_hat|`` beyond which the internal model counts as diverged.
    w : ndarray, shape (N, m)
        Receives ``w_hat``.
    x : ndarray, shape (N,)
        Receives ``x_hat`` (``y`` without output block).
    hist : ndarray, shape (M, n)
        Receives ``theta`` after every ``hist_stride``-th update (M may be 0).
    err : ndarray, shape (N,)
        Receives the a-priori error of every updated sample.

    Returns
    -------
    status, reason : int
        ``OK`` or the index of the failing sample; ``REASON_OK``, ``REASON_STEP`` or
        ``REASON_EXPLODED``.
    """
    nb, na, r2 = orders[0], orders[1], orders[2]
    has_in, has_out = orders[3] != 0, orders[4] != 0
    n0, stride, start = orders[5], orders[6], orders[7]
    trace_max, x_limit = limits[0], limits[1]
    N, m, nf = phi_u.shape[0], phi_u.shape[1], phi_u.shape[2]
    n = theta.shape[0]
    bias = orders[8] != 0 and not has_in and has_out
    # gamma_0, then every channel's gammas; or a Wiener model's output bias h
    n_in = 1 + m * nf if has_in else (1 if bias else 0)
    b_first = 1 if has_in else 0  # b_{c,0} = 1 is the key term with input blocks
    nbf = nb - b_first  # free b's per channel
    ib = n_in
    ia = ib + m * nbf
    iq = ia + na
    phi = np.empty(n)
    g = np.empty(n)
    out = np.empty(2)
    row = 0
    for k in range(start, N):
        # w_hat(k) of every channel from the newest estimates
        for c in range(m):
            if has_in:
                wk = theta[0] if c == 0 else 0.0
                at = 1 + c * nf
                for j in range(nf):
                    wk += theta[at + j] * phi_u[k, c, j]
                w[k, c] = wk
            else:
                w[k, c] = phi_u[k, c, 0]
        # x_hat(k): the linear block on w_hat and past x_hat
        if has_out:
            xk = 0.0
            for c in range(m):
                lag0 = k - delays[c]
                if has_in and lag0 >= 0:
                    xk += w[lag0, c]  # b_{c,0} = 1
                for i in range(b_first, nb):
                    if lag0 - i >= 0:
                        xk += theta[ib + c * nbf + i - b_first] * w[lag0 - i, c]
            xk = minus_ar(xk, theta, x, k, na, ia)
            if not (abs(xk) <= x_limit):  # also catches NaN
                return k, REASON_EXPLODED
            x[k] = xk
        else:
            x[k] = y[k]
        if k < n0:
            continue
        # regressor Phi_hat(k)
        if bias:
            phi[0] = 1.0
        if has_in:
            phi[0] = 1.0
            for c in range(m):
                at = 1 + c * nf
                kd = k - delays[c]
                for j in range(nf):
                    phi[at + j] = phi_u[kd, c, j]
        for c in range(m):
            kd = k - delays[c]
            for i in range(b_first, nb):
                phi[ib + c * nbf + i - b_first] = w[kd - i, c]
        sizes = (na, ia, iq, r2, n0, stride)
        row = output_step(theta, P, phi, g, out, x, y[k], k, lam[k], sizes, has_out,
                          trace_max, err, hist, row)  # fmt: skip
        if row < 0:
            return k, REASON_STEP
    return OK, REASON_OK
