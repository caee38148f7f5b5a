"""Numba kernels of the backlash block, SPEC.md equations (A3) and (A4).

The kernels work on plain floats and arrays and do no validation: the public
:class:`blockid.blocks.backlash.Backlash` checks its parameters and inputs first.
``backlash_step`` is the single update rule; estimator kernels (A7) may call it too.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["backlash_step", "backlash_run"]


@njit(cache=True)
def backlash_step(u, x_prev, m_left, c_left, m_right, c_right):
    """Advance the backlash by one sample.

    Parameters
    ----------
    u : float
        Input ``u(t)``.
    x_prev : float
        Previous output ``x(t-1)``.
    m_left, c_left, m_right, c_right : float
        Slopes and dead-band half-widths (``m > 0``, ``c >= 0``).

    Returns
    -------
    x : float
        Output ``x(t)`` by the three branches of (A3).
    f1, f2 : float
        Switching values of (A4): ``f1 = h(u - zL)`` (1.0 while driving left),
        ``f2 = h(zR - u)`` (1.0 while driving right), ``h(s) = 1`` for ``s <= 0``.
    """
    z_left = x_prev / m_left - c_left  # zL(t) = x(t-1)/mL - cL        (A3)
    z_right = x_prev / m_right + c_right  # zR(t) = x(t-1)/mR + cR       (A3)
    f1 = 1.0 if u - z_left <= 0.0 else 0.0  # f1(t) = h(u(t) - zL(t))   (A4)
    f2 = 1.0 if z_right - u <= 0.0 else 0.0  # f2(t) = h(zR(t) - u(t))  (A4)
    if u < z_left:
        x = m_left * (u + c_left)  # left branch                         (A3)
    elif u > z_right:
        x = m_right * (u - c_right)  # right branch                      (A3)
    else:
        x = x_prev  # dead band: the output holds                         (A3)
    return x, f1, f2


@njit(cache=True)
def backlash_run(u, theta, x0):
    """Run the backlash over a whole input sequence.

    Parameters
    ----------
    u : ndarray of float64, shape (n,)
        Input sequence.
    theta : ndarray of float64, shape (4,)
        ``[m_left, c_left, m_right, c_right]``.
    x0 : float
        Output before the first sample, ``x(-1)``.

    Returns
    -------
    x, f1, f2 : ndarray of float64, shape (n,)
        Output (A3) and the switching sequences (A4).
    """
    n = u.shape[0]
    x = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    x_prev = x0
    for t in range(n):
        x[t], f1[t], f2[t] = backlash_step(u[t], x_prev, theta[0], theta[1], theta[2], theta[3])
        x_prev = x[t]
    return x, f1, f2
