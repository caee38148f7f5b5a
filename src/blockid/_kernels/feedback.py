"""Numba kernels of the linear block with a polynomial in feedback (Lur'e form).

.. math::

    y(t) = -\\sum_{j=1}^{n_a} a_j\\, y(t - j)
           + \\sum_{i=0}^{n_b - 1} b_i\\, v(t - n_k - i),
    \\qquad v(t) = u(t) - N(y(t)), \\qquad N(y) = \\sum_{m=1}^{r} c_m y^m

(:mod:`blockid.models.feedback`; ``n_k >= 1``, so ``y(t)`` needs only past ``v``). One
update rule, :func:`lagged_sum`, gives the output and every column of its sensitivities:
differentiating the recursion with respect to ``θ = [a, b, c]`` gives the same recursion
for ``∂y/∂θ``, driven through the feedback by ``∂v/∂θ = -N'(y)\\, ∂y/∂θ - ∂N/∂θ``,

.. math::

    \\frac{\\partial y(t)}{\\partial \\theta}
        = -\\sum_j a_j \\frac{\\partial y(t-j)}{\\partial \\theta}
          + \\sum_i b_i \\frac{\\partial v(t-n_k-i)}{\\partial \\theta}
          + \\begin{cases} -y(t - j) & \\theta = a_j \\\\
                           v(t - n_k - i) & \\theta = b_i \\\\
                           0 & \\theta = c_m \\end{cases},
    \\qquad
    \\frac{\\partial v(t)}{\\partial c_m} \\mathrel{+}= -y(t)^m .

Rows before ``n0`` hold given outputs (measured, relative to the offset): their ``v`` is
computed from them and their sensitivities are zero, except ``∂v/∂c_m = -y^m``. Signals
before ``t = 0`` count as zero.

Other static blocks in feedback (:class:`~blockid.models.feedback.LinearFeedback`):

* **Piecewise-linear blocks** (dead zone, saturation, piecewise-linear maps, with fixed
  or free breakpoints) are simulated by :func:`feedback_simulate_table`, which evaluates
  ``N`` from breakpoints, values and the two end slopes (:func:`table_value`).
* **Sensitivities of any block** come from :func:`feedback_sensitivity_given`: once the
  simulation has fixed ``y``, ``N'(y(t))`` and ``∂N(y(t))/∂θ_N`` are known arrays (the
  block evaluates them on the whole record at once), and the sensitivity recursion
  above is linear in ``∂y/∂θ`` with those arrays as coefficients and forcing. For a
  polynomial it gives what :func:`feedback_sensitivity` gives (a test checks this).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "feedback_sensitivity",
    "feedback_sensitivity_given",
    "feedback_simulate",
    "feedback_simulate_table",
    "lagged_sum",
    "polynomial_value",
    "table_value",
]


@njit(cache=True)
def polynomial_value(c, y):
    """``N(y) = sum_m c[m-1] y^m`` (no constant) and ``N'(y)``, by Horner's rule."""
    p = 0.0  # P(y) = c_1 + c_2 y + ..., N = y P
    dp = 0.0  # P'(y)
    for m in range(c.shape[0] - 1, -1, -1):
        dp = dp * y + p
        p = p * y + c[m]
    return y * p, p + y * dp


@njit(cache=True)
def lagged_sum(a, b, nk, s, w, t):
    """``-sum_j a_j s(t-j) + sum_i b_i w(t-nk-i)`` (zero before ``t = 0``): the recursion."""
    acc = 0.0
    for j in range(1, min(a.shape[0], t) + 1):
        acc -= a[j - 1] * s[t - j]
    for i in range(b.shape[0]):
        d = t - nk - i
        if d < 0:
            break
        acc += b[i] * w[d]
    return acc


@njit(cache=True)
def feedback_simulate(a, b, c, nk, u, y, n0):
    """Free-run simulation in place.

    Parameters
    ----------
    a, b, c : ndarray of float64
        ``[a_1..a_na]``, ``[b_0..b_{nb-1}]``, ``[c_1..c_r]``.
    nk : int
        Input delay, ``>= 1``.
    u : ndarray of float64, shape (N,)
        Input (relative to the offset).
    y : ndarray of float64, shape (N,)
        Rows ``:n0`` hold the initial outputs; rows ``n0..`` are overwritten.
    n0 : int

    Returns
    -------
    v : ndarray, shape (N,)
        ``u - N(y)``, the input of the linear block.
    """
    N = y.shape[0]
    v = np.empty(N)
    for t in range(N):
        if t >= n0:
            y[t] = lagged_sum(a, b, nk, y, v, t)
        f, _ = polynomial_value(c, y[t])
        v[t] = u[t] - f
    return v


@njit(cache=True)
def feedback_sensitivity(a, b, c, nk, u, y, n0):
    """:func:`feedback_simulate` with the sensitivities of ``y`` to ``[a, b, c]``.

    Returns
    -------
    v : ndarray, shape (N,)
    dy : ndarray, shape (na + nb + r, N)
        ``dy[p, t] = ∂y(t)/∂θ_p`` for ``θ = [a_1..a_na, b_0..b_{nb-1}, c_1..c_r]``
        (one contiguous row per parameter).
    """
    N = y.shape[0]
    na, nb, r = a.shape[0], b.shape[0], c.shape[0]
    n = na + nb + r
    v = np.empty(N)
    dy = np.zeros((n, N))
    dv = np.zeros((n, N))
    for t in range(N):
        if t >= n0:
            y[t] = lagged_sum(a, b, nk, y, v, t)
            for p in range(n):  # the same recursion for every sensitivity
                dy[p, t] = lagged_sum(a, b, nk, dy[p], dv[p], t)
            for j in range(1, min(na, t) + 1):  # a_j: -y(t-j)
                dy[j - 1, t] -= y[t - j]
            for i in range(nb):  # b_i: v(t-nk-i)
                if t - nk - i < 0:
                    break
                dy[na + i, t] += v[t - nk - i]
        f, df = polynomial_value(c, y[t])
        v[t] = u[t] - f
        for p in range(n):  # v = u - N(y): chain rule through N'(y)
            dv[p, t] = -df * dy[p, t]
        power = y[t]
        for m in range(r):  # c_m: -y^m
            dv[na + nb + m, t] -= power
            power *= y[t]
    return v, dy


@njit(cache=True)
def table_value(xs, ys, slope_left, slope_right, x):
    """The piecewise-linear map through ``(xs, ys)`` at ``x`` (``xs`` non-decreasing),
    continued beyond the end breakpoints with the given end slopes."""
    n = xs.shape[0]
    if x != x:  # NaN (an exploding run): stays NaN, never a division by zero below
        return x
    if x <= xs[0]:
        return ys[0] + slope_left * (x - xs[0])
    if x >= xs[n - 1]:
        return ys[n - 1] + slope_right * (x - xs[n - 1])
    lo, hi = 0, n - 1  # bisection: xs[lo] < x < xs[hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    width = xs[hi] - xs[lo]
    if width <= 0.0:  # coincident breakpoints: a jump, taken at its left value
        return ys[lo]
    return ys[lo] + (x - xs[lo]) * (ys[hi] - ys[lo]) / width


@njit(cache=True)
def feedback_simulate_table(a, b, xs, ys, slope_left, slope_right, nk, u, y, n0):
    """:func:`feedback_simulate` with a piecewise-linear ``N`` (:func:`table_value`)."""
    N = y.shape[0]
    v = np.empty(N)
    for t in range(N):
        if t >= n0:
            y[t] = lagged_sum(a, b, nk, y, v, t)
        v[t] = u[t] - table_value(xs, ys, slope_left, slope_right, y[t])
    return v


@njit(cache=True)
def feedback_sensitivity_given(a, b, nk, y, v, slope, forcing, n0):
    """Sensitivities of a simulated loop with any static block ``N`` in feedback.

    Parameters
    ----------
    a, b : ndarray of float64
    nk : int
    y, v : ndarray of float64, shape (N,)
        The simulated output and ``u - N(y)`` (from a simulation kernel).
    slope : ndarray of float64, shape (N,)
        ``N'(y(t))``.
    forcing : ndarray of float64, shape (p, N)
        ``∂N(y(t))/∂θ_m`` for the block's ``p`` parameters (one row each).
    n0 : int
        Rows before ``n0`` hold given outputs (zero sensitivity).

    Returns
    -------
    dy : ndarray, shape (na + nb + p, N)
        ``∂y(t)/∂θ`` for ``θ = [a_1..a_na, b_0..b_{nb-1}, θ_N]``.
    """
    N = y.shape[0]
    na, nb, p = a.shape[0], b.shape[0], forcing.shape[0]
    n = na + nb + p
    dy = np.zeros((n, N))
    dv = np.zeros((n, N))
    for t in range(N):
        if t >= n0:
            for q in range(n):
                dy[q, t] = lagged_sum(a, b, nk, dy[q], dv[q], t)
            for j in range(1, min(na, t) + 1):
                dy[j - 1, t] -= y[t - j]
            for i in range(nb):
                if t - nk - i < 0:
                    break
                dy[na + i, t] += v[t - nk - i]
        for q in range(n):
            dv[q, t] = -slope[t] * dy[q, t]
        for m in range(p):
            dv[na + nb + m, t] -= forcing[m, t]
    return dy
