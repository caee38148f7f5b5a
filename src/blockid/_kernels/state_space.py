"""Numba kernels of (polynomial) nonlinear state-space models: simulation and the exact
Jacobian of the simulated output, computed forward in time.

The model, in the signals' normalised units (``docs/models.md``, Paduart et al.,
Automatica 46, 2010):

.. math::

    x(k+1) = A x(k) + B u(k) + E\\, \\zeta(k), \\qquad
    y(k) = C x(k) + D u(k) + F\\, \\zeta(k)

with ``ζ(k)`` the monomials of ``z = [x(k); u(k)]`` listed by the rows of ``expo``
(``ζ_j = Π_i z_i^{expo[j, i]}``), each coordinate clipped to ``[lo_i, hi_i]`` before
the monomials are taken: beyond the range the nonlinear terms hold their boundary
values, so with a stable ``A`` a free run stays bounded whatever the input does (the
linear part is never clipped). A linear state-space model has no monomials.

The parameters ``θ = [A, B, C, D, E, F]`` (each row-major) and the initial state
``x(0)`` (the last ``nx`` columns) are differentiated together:

.. math::

    S(k+1) = (A + E\\, \\partial\\zeta/\\partial x)\\, S(k) + G(k), \\qquad
    \\partial y(k)/\\partial\\theta = (C + F\\, \\partial\\zeta/\\partial x)\\, S(k) + H(k)

where ``S = ∂x/∂θ`` starts as ``[0 | I]`` (only ``x(0)`` moves ``x(0)``) and ``G``, ``H``
are the explicit derivatives (``∂x(k+1)/∂A_ij = x_j(k)`` in row ``i``, and so on). A
clipped coordinate has zero slope.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["channel_response", "monomials", "pnlss_jacobian", "pnlss_simulate"]


@njit(cache=True)
def monomials(z, expo, lo, hi, out):
    """``out[j] = Π_i clip(z_i, lo_i, hi_i) ** expo[j, i]``."""
    nm, nz = expo.shape
    for j in range(nm):
        val = 1.0
        for i in range(nz):
            p = expo[j, i]
            if p:
                zi = min(max(z[i], lo[i]), hi[i])
                val *= zi**p
        out[j] = val


@njit(cache=True)
def _slopes(z, expo, lo, hi, nx, out):
    """``out[j, i] = ∂ζ_j / ∂x_i`` (0 where ``x_i`` is clipped)."""
    nm, nz = expo.shape
    for j in range(nm):
        for i in range(nx):
            p = expo[j, i]
            if p == 0 or not (lo[i] < z[i] < hi[i]):
                out[j, i] = 0.0
                continue
            d = p * z[i] ** (p - 1)
            for k in range(nz):
                q = expo[j, k]
                if k != i and q:
                    zk = min(max(z[k], lo[k]), hi[k])
                    d *= zk**q
            out[j, i] = d


@njit(cache=True)
def pnlss_simulate(A, B, C, D, E, F, expo, lo, hi, u, x, y):
    """Free run from state ``x`` (updated in place to the state after the last sample).

    Parameters
    ----------
    A, B, C, D, E, F : ndarray of float64
        Shapes (nx, nx), (nx, nu), (ny, nx), (ny, nu), (nx, nm), (ny, nm).
    expo : ndarray of int64, shape (nm, nx + nu)
    lo, hi : ndarray of float64, shape (nx + nu,)
    u : ndarray of float64, shape (N, nu)
    x : ndarray of float64, shape (nx,)
    y : ndarray of float64, shape (N, ny)
        Receives the output.

    Returns
    -------
    bool
        False if the run became non-finite (the rest of ``y`` is then NaN).
    """
    N = u.shape[0]
    nx, nu, ny, nm = A.shape[0], B.shape[1], C.shape[0], expo.shape[0]
    z = np.empty(nx + nu)
    zeta = np.empty(nm)
    xn = np.empty(nx)
    for k in range(N):
        for i in range(nx):
            z[i] = x[i]
        for i in range(nu):
            z[nx + i] = u[k, i]
        monomials(z, expo, lo, hi, zeta)
        for i in range(ny):
            acc = 0.0
            for j in range(nx):
                acc += C[i, j] * x[j]
            for j in range(nu):
                acc += D[i, j] * u[k, j]
            for j in range(nm):
                acc += F[i, j] * zeta[j]
            y[k, i] = acc
        finite = True
        for i in range(nx):
            acc = 0.0
            for j in range(nx):
                acc += A[i, j] * x[j]
            for j in range(nu):
                acc += B[i, j] * u[k, j]
            for j in range(nm):
                acc += E[i, j] * zeta[j]
            xn[i] = acc
            if not np.isfinite(acc):
                finite = False
        if not finite:
            y[k + 1 :, :] = np.nan
            return False
        for i in range(nx):
            x[i] = xn[i]
    return True


@njit(cache=True, nogil=True)
def pnlss_jacobian(A, B, C, D, E, F, expo, lo, hi, u, x, S, y, J):
    """Free run and ``∂y/∂[θ, x(0)]`` over a piece of a record, carrying the state.

    ``x`` (nx,) and ``S`` (nx, P) hold the state and its sensitivity at the piece's
    first sample and are updated in place to those after its last (so a record can be
    walked in pieces; start with ``S = [0 | I]``). ``P`` is the number of model
    parameters plus ``nx`` (the initial state). Row ``k * ny + i`` of ``J`` (N ny, P)
    receives ``∂y_i(k)/∂[θ, x(0)]``; ``y`` (N, ny) the output.
    """
    N = u.shape[0]
    nx, nu, ny, nm = A.shape[0], B.shape[1], C.shape[0], expo.shape[0]
    P = S.shape[1]
    o_b = nx * nx
    o_c = o_b + nx * nu
    o_d = o_c + ny * nx
    o_e = o_d + ny * nu
    o_f = o_e + nx * nm
    z = np.empty(nx + nu)
    zeta = np.empty(nm)
    dz = np.empty((nm, nx))
    jx = np.empty((nx, nx))
    jy = np.empty((ny, nx))
    xn = np.empty(nx)
    Sn = np.empty((nx, P))
    for k in range(N):
        for i in range(nx):
            z[i] = x[i]
        for i in range(nu):
            z[nx + i] = u[k, i]
        monomials(z, expo, lo, hi, zeta)
        _slopes(z, expo, lo, hi, nx, dz)
        # the local Jacobians of the output and state maps with respect to x
        for i in range(ny):
            for j in range(nx):
                acc = C[i, j]
                for m in range(nm):
                    acc += F[i, m] * dz[m, j]
                jy[i, j] = acc
        for i in range(nx):
            for j in range(nx):
                acc = A[i, j]
                for m in range(nm):
                    acc += E[i, m] * dz[m, j]
                jx[i, j] = acc
        # output and its sensitivity
        for i in range(ny):
            acc = 0.0
            for j in range(nx):
                acc += C[i, j] * x[j]
            for j in range(nu):
                acc += D[i, j] * u[k, j]
            for j in range(nm):
                acc += F[i, j] * zeta[j]
            y[k, i] = acc
            row = k * ny + i
            for p in range(P):
                J[row, p] = 0.0
            for j in range(nx):
                c = jy[i, j]
                if c != 0.0:
                    for p in range(P):
                        J[row, p] += c * S[j, p]
            for j in range(nx):
                J[row, o_c + i * nx + j] += x[j]
            for j in range(nu):
                J[row, o_d + i * nu + j] += u[k, j]
            for j in range(nm):
                J[row, o_f + i * nm + j] += zeta[j]
        # state and its sensitivity
        for i in range(nx):
            acc = 0.0
            for j in range(nx):
                acc += A[i, j] * x[j]
            for j in range(nu):
                acc += B[i, j] * u[k, j]
            for j in range(nm):
                acc += E[i, j] * zeta[j]
            xn[i] = acc
            for p in range(P):
                Sn[i, p] = 0.0
            for j in range(nx):
                c = jx[i, j]
                if c != 0.0:
                    for p in range(P):
                        Sn[i, p] += c * S[j, p]
            for j in range(nx):
                Sn[i, i * nx + j] += x[j]
            for j in range(nu):
                Sn[i, o_b + i * nu + j] += u[k, j]
            for j in range(nm):
                Sn[i, o_e + i * nm + j] += zeta[j]
        for i in range(nx):
            x[i] = xn[i]
            for p in range(P):
                S[i, p] = Sn[i, p]


@njit(cache=True, nogil=True)
def channel_response(A, B, C, D, chans, G, X, out):
    """Response of the linear system ``(A, B, C, D)`` to each column of ``G`` entering
    the input channel ``chans[q]``, carrying the states.

    ``G`` (N, p) holds the columns, ``X`` (nx, p) their states at the piece's first
    sample (updated in place to those after its last), ``out`` (N, ny, p) receives the
    outputs. Used for the sensitivity of a linear core's output to the parameters of a
    static block before its input ``chans[q]``: ``∂x(k+1)/∂θ = A ∂x(k)/∂θ + B_i ∂w_i/∂θ``.
    """
    N, p = G.shape
    nx, ny = A.shape[0], C.shape[0]
    Xn = np.empty((nx, p))
    for k in range(N):
        for i in range(ny):
            for q in range(p):
                acc = D[i, chans[q]] * G[k, q]
                for j in range(nx):
                    acc += C[i, j] * X[j, q]
                out[k, i, q] = acc
        for i in range(nx):
            for q in range(p):
                acc = B[i, chans[q]] * G[k, q]
                for j in range(nx):
                    acc += A[i, j] * X[j, q]
                Xn[i, q] = acc
        for i in range(nx):
            for q in range(p):
                X[i, q] = Xn[i, q]
