"""Compiled free-run simulation of multi-input multi-output ARX models."""

from __future__ import annotations

from numba import njit

__all__ = ["arx_simulate"]


@njit(cache=True)
def arx_simulate(A, B, u, y, n0):
    """Free-run simulation in place.

    ``A[i, j, k]`` multiplies ``-y_j(t-k)`` in output i (k >= 1), ``B[i, m, l]`` multiplies
    ``u_m(t-l)`` (l >= 0, input delays included as leading zeros). ``y[:n0]`` holds the
    initial conditions; samples ``n0..N-1`` are overwritten with the model output
    computed from its own past outputs. Signals before ``t = 0`` count as zero.
    """
    N, ny = y.shape
    nu = u.shape[1]
    La = A.shape[2]
    Lb = B.shape[2]
    for t in range(n0, N):
        for i in range(ny):
            acc = 0.0
            for j in range(ny):
                for k in range(1, min(La, t + 1)):
                    acc -= A[i, j, k] * y[t - k, j]
            for m in range(nu):
                for lag in range(Lb):
                    if t - lag >= 0:
                        acc += B[i, m, lag] * u[t - lag, m]
            y[t, i] = acc
