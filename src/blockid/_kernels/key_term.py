"""Key-term RLS with internal-variable estimation: paper B's recursion (B4, B5).

One pass of the recursion over one experiment. Per sample ``k`` (``theta`` the newest
estimate, i.e. :math:`\\hat\\theta(k-1)`):

.. math::

    \\hat w(k) = \\sum_l \\hat f_l u^l(k) + \\sum_l \\hat p_l u^l(k) h(u(k))

    \\hat x(k) = \\hat w(k-n_k) + \\sum_{i\\ge 1} \\hat b_i \\hat w(k-n_k-i)
                - \\sum_j \\hat a_j \\hat x(k-j)

    \\hat\\Phi(k) = [1, u, .., u^{r_1}, h, u h, .., u^{r_1} h\\ (\\text{at } k-n_k),\\;
        \\hat w(k-n_k-1)..,\\; -\\hat x(k-1)..,\\; \\hat x^2(k)..\\hat x^{r_2}(k)]

then one RLS step (:func:`blockid._kernels.rls.rls_step`, B5) on ``y(k)``.

Structures (``orders[5]``, ``orders[6]`` switch the blocks off):

* no input block (Wiener, ARX): ``w = u`` and ``b_0`` is free, so the ``b`` part of the
  regressor starts at ``w(k - nk)`` and there are no ``f, p`` columns;
* no output block (Hammerstein, ARX): ``x = y`` is measured, so the ``-x(k-j)``
  columns hold the measured output and there are no ``q`` columns (ARX is then plain
  RLS).

Values before the start of the record are 0 (the paper's ``x(0) = w(0) = u(0) = 0``).
The internal variables are computed from sample 0, the parameters updated only from
sample ``n0 = max_lag`` on, where every regressor entry refers to a sample of the
record.

Continuation (online learning, :mod:`blockid.fitting.online`): with a tenth entry
``start`` in ``orders``, samples ``k < start`` are history: their ``u, y, w, x`` are
used as given and nothing is computed or updated for them. A pass over a record can
so be split into chunks, each preceded by the last ``max_lag`` samples of the one
before (``n0`` and ``lam`` then counted in the chunk's own indices), with the same
result as one pass.

Parameter vector (B4): ``[f_0..f_r1, p_0..p_r1, b_1..b_{nb-1}, a_1..a_na, q_2..q_r2]``
(``b_0..b_{nb-1}`` without an input block; MATLAB order convention, ``nb`` counts
``b_0``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from blockid._kernels.rls import OK, recorded_step, rls_step

__all__ = [
    "OK",
    "REASON_OK",
    "REASON_STEP",
    "REASON_EXPLODED",
    "key_term_run",
    "key_term_step",
    "window_commit",
]

#: Failure reasons returned next to the sample index.
REASON_OK = 0
REASON_STEP = 1  # the RLS step (or its error) was not finite, or P lost definiteness
REASON_EXPLODED = 2  # |x_hat| exceeded the limit: the internal model diverged


@njit(cache=True)
def key_term_run(theta, P, u, y, lam, orders, limits, w, x, hist, err=None):
    """One pass of key-term RLS (B5) over one experiment, in place.

    Parameters
    ----------
    theta, P : ndarray
        Estimate and covariance, updated in place.
    u, y : ndarray, shape (N,)
        Input and measured output.
    lam : ndarray, shape (N,)
        Forgetting factor of every sample (entries before ``n0`` are not used).
    orders : ndarray of int64
        ``[r1, nb, na, r2, nk, has_input_block, has_output_block, n0, hist_stride]``,
        optionally followed by ``start`` (default 0): samples before it are history,
        used as given (module docstring).
    limits : ndarray of float
        ``[trace_max, x_limit]``: trace bound of ``P`` (used while ``lam < 1``) and the
        bound on ``|x_hat|`` beyond which the internal model counts as diverged.
    w, x : ndarray, shape (N,)
        Receive the internal variables ``w_hat`` and ``x_hat`` (``x = y`` without
        output block).
    hist : ndarray, shape (M, n)
        Receives ``theta`` after every ``hist_stride``-th update (M may be 0).
    err : ndarray, shape (N,), optional
        Receives the a-priori error ``y(k) - Phi_hat(k)^T theta(k-1)`` of every updated
        sample (other entries untouched).

    Returns
    -------
    status : int
        ``OK`` or the index of the sample at which the pass failed.
    reason : int
        ``REASON_OK``, ``REASON_STEP`` or ``REASON_EXPLODED``.
    """
    r1, nb, na, r2, nk = orders[0], orders[1], orders[2], orders[3], orders[4]
    has_in, has_out, n0, stride = orders[5] != 0, orders[6] != 0, orders[7], orders[8]
    trace_max, x_limit = limits[0], limits[1]
    start = orders[9] if orders.shape[0] > 9 else 0
    N = u.shape[0]
    n = theta.shape[0]
    n_in = 2 * (r1 + 1) if has_in else 0
    b_first = 1 if has_in else 0  # b_0 = 1 is the key term with an input block
    ib = n_in  # start of the b's in theta
    ia = ib + nb - b_first  # start of the a's
    iq = ia + na  # start of the q's
    phi = np.empty(n)
    g = np.empty(n)
    out = np.empty(2)
    row = 0
    for k in range(start, N):
        # w_hat(k) from the newest estimates                               (B1, B5)
        uk = u[k]
        if has_in:
            fu = 0.0
            pu = 0.0
            for l in range(r1, -1, -1):  # Horner
                fu = fu * uk + theta[l]
                pu = pu * uk + theta[r1 + 1 + l]
            w[k] = fu + pu if uk < 0.0 else fu
        else:
            w[k] = uk
        # x_hat(k): linear block on w_hat and past x_hat                   (B5)
        if has_out:
            xk = 0.0
            if has_in and k - nk >= 0:
                xk = w[k - nk]  # b_0 = 1
            for i in range(b_first, nb):
                j = k - nk - i
                if j >= 0:
                    xk += theta[ib + i - b_first] * w[j]
            xk = minus_ar(xk, theta, x, k, na, ia)
            if not (abs(xk) <= x_limit):  # also catches NaN
                return k, REASON_EXPLODED
            x[k] = xk
        else:
            x[k] = y[k]  # no output block: x is the measured output
        if k < n0:
            continue
        # regressor Phi_hat(k)                                             (B4, B5)
        if has_in:
            ud = u[k - nk]
            hd = 1.0 if ud < 0.0 else 0.0  # h(u) = 1 for u < 0              (B1)
            pw = 1.0
            for l in range(r1 + 1):
                phi[l] = pw
                phi[r1 + 1 + l] = pw * hd
                pw *= ud
        for i in range(b_first, nb):
            phi[ib + i - b_first] = w[k - nk - i]
        sizes = (na, ia, iq, r2, n0, stride)
        row = output_step(theta, P, phi, g, out, x, y[k], k, lam[k], sizes, has_out,
                          trace_max, err, hist, row)  # fmt: skip
        if row < 0:
            return k, REASON_STEP
    return OK, REASON_OK


@njit(cache=True)
def minus_ar(xk, theta, x, k, na, ia):
    """``xk - Σ_j a_j x(k-j)`` (``a_j = theta[ia + j - 1]``, past values before the record
    0), subtracted term by term."""
    for j in range(1, na + 1):
        if k - j >= 0:
            xk -= theta[ia + j - 1] * x[k - j]
    return xk


@njit(cache=True)
def output_step(theta, P, phi, g, out, x, yk, k, lk, sizes, has_out, trace_max, err, hist, row):
    """The end of one sample of the key-term recursions (this module's and
    :mod:`blockid._kernels.key_term_channels`): the regressor's output part (``-x(k-j)``,
    ``x(k)^m``), the RLS step (B5) and its record (:func:`~blockid._kernels.rls.recorded_step`:
    the a-priori error into ``err`` if given, ``theta`` into ``hist`` every ``stride``-th
    update). ``sizes = (na, ia, iq, r2, n0, stride)``. Returns the next history row, or
    -1 when the step failed."""
    na, ia, iq, r2, n0, stride = sizes
    for j in range(1, na + 1):
        phi[ia + j - 1] = -x[k - j]
    if has_out:
        pw = x[k]
        for m in range(2, r2 + 1):
            pw *= x[k]
            phi[iq + m - 2] = pw
    bound = trace_max if lk < 1.0 else np.inf
    ok = rls_step(theta, P, phi, yk, g, lk, 1.0, 1.0 / lk, bound, out)
    return recorded_step(ok, theta, out, err, hist, k, n0, stride, row)


@njit(cache=True)
def window_commit(status, theta, P, saved_theta, saved_P, window):
    """After a one-sample continuation over ``window`` (rows: signals, last column the
    new sample): on success shift every row left by one (the oldest sample drops out),
    on failure restore ``theta`` and ``P`` from the saved copies."""
    if status == OK:
        for r in range(window.shape[0]):
            for j in range(window.shape[1] - 1):
                window[r, j] = window[r, j + 1]
    else:
        theta[:] = saved_theta
        P[:, :] = saved_P


@njit(cache=True)
def key_term_step(theta, P, window, uk, yk, lam_k, n0, orders, limits, saved, hist):
    """One sample of key-term RLS continued from a window (the online per-sample path).

    ``window`` has rows ``u, y, w_hat, x_hat`` and ``L + 1`` columns: the last ``L =
    orders[9]`` samples, then a free slot that receives ``uk, yk``. Runs
    :func:`key_term_run` over the window with ``start = L``, the first update at
    ``n0`` (``orders[7]``) and ``lam_k`` for the new sample, then shifts the window on
    success or restores ``theta``, ``P`` (from ``saved = (theta copy, P copy)``
    buffers, ``saved[0]`` of shape (n + n*n,)) on failure. Returns ``(status, reason,
    e)`` with the a-priori error ``e`` of the new sample (NaN without an update).
    """
    L = window.shape[1] - 1
    n = theta.shape[0]
    window[0, L] = uk
    window[1, L] = yk
    orders[7] = n0
    lam = np.ones(L + 1)
    lam[L] = lam_k
    err = np.full(L + 1, np.nan)
    saved[:n] = theta
    saved[n:] = P.ravel()
    status, reason = key_term_run(
        theta, P, window[0], window[1], lam, orders, limits, window[2], window[3], hist, err
    )
    window_commit(status, theta, P, saved[:n], saved[n:].reshape(n, n), window)
    return status, reason, err[L]
