"""Numba kernels for free-run simulation with parameter sensitivities.

The refinement on simulation error (:mod:`blockid.fitting.simulation_error`) needs the
derivative of the simulated output with respect to every parameter. For the linear
block of a block-oriented model both the output and its sensitivities obey the same
all-pole recursion with different forcing terms, so one kernel serves both:

.. math::

    s(t) = F(t) - \\sum_{j=1}^{n_a} a_j\\, s(t - j), \\qquad t \\ge n_0

(SPEC (A5), (B2) with the numerator already applied to the forcing ``F``). The backlash
(A3) output is piecewise linear in its parameters; ``backlash_sensitivity`` runs the
block with :func:`blockid._kernels.backlash.backlash_step` and carries the derivative of
the active branch (held through the dead band).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from blockid._kernels.backlash import backlash_step

__all__ = ["allpole_run", "backlash_sensitivity"]


@njit(cache=True)
def allpole_run(a, F, S, n0):
    """All-pole recursion over several columns, in place.

    Parameters
    ----------
    a : ndarray of float64, shape (na,)
        ``[a_1..a_na]`` of ``A(z^-1) = 1 + a_1 z^-1 + ...``.
    F : ndarray of float64, shape (N, m)
        Forcing of each column.
    S : ndarray of float64, shape (N, m)
        Rows ``:n0`` hold the initial values; rows ``n0..N-1`` are overwritten with
        ``S[t] = F[t] - sum_j a_j S[t - j]`` (values before ``t = 0`` count as zero,
        as in :func:`blockid._kernels.arx.arx_simulate`).
    n0 : int
    """
    N, m = S.shape
    na = a.shape[0]
    for t in range(n0, N):
        for c in range(m):
            acc = F[t, c]
            for j in range(1, min(na, t) + 1):
                acc -= a[j - 1] * S[t - j, c]
            S[t, c] = acc


@njit(cache=True)
def backlash_sensitivity(u, theta, x0, dx0):
    """Backlash output (A3) and its derivative with respect to ``theta``.

    Parameters
    ----------
    u : ndarray of float64, shape (N,)
        Input sequence.
    theta : ndarray of float64, shape (4,)
        ``[m_left, c_left, m_right, c_right]``.
    x0 : float
        Output before the first sample.
    dx0 : ndarray of float64, shape (4,)
        Derivative of ``x0`` with respect to ``theta``.

    Returns
    -------
    x : ndarray, shape (N,)
    dx : ndarray, shape (N, 4)
        On the left branch ``x = m_L (u + c_L)``, on the right branch
        ``x = m_R (u - c_R)``; in the dead band the derivative of ``x(t-1)`` is held.
        At a branch boundary (``f1`` or ``f2`` of (A4) equal to 1 with the output
        held) the branch's one-sided derivative is used; the output is continuous
        there.
    """
    N = u.shape[0]
    x = np.empty(N)
    dx = np.empty((N, 4))
    x_prev = x0
    d_prev = dx0.copy()
    for t in range(N):
        x[t], f1, f2 = backlash_step(u[t], x_prev, theta[0], theta[1], theta[2], theta[3])
        if f1 == 1.0:  # driving left: x = mL (u + cL)
            dx[t, 0] = u[t] + theta[1]
            dx[t, 1] = theta[0]
            dx[t, 2] = 0.0
            dx[t, 3] = 0.0
        elif f2 == 1.0:  # driving right: x = mR (u - cR)
            dx[t, 0] = 0.0
            dx[t, 1] = 0.0
            dx[t, 2] = u[t] - theta[3]
            dx[t, 3] = -theta[2]
        else:  # dead band: x(t) = x(t-1)
            for k in range(4):
                dx[t, k] = d_prev[k]
        x_prev = x[t]
        for k in range(4):
            d_prev[k] = dx[t, k]
    return x, dx
