"""Numba kernels of a state-space core with static blocks inside its loop.

.. math::

    p(k) = C_p x(k) + D_p w(k), \\qquad q_l(k) = \\varphi_l(p_l(k)), \\\\
    x(k+1) = A x(k) + B w(k) + B_q q(k) + e, \\qquad
    z(k) = C x(k) + D w(k) + D_q q(k)

(:class:`~blockid.models.block_state_space.BlockStateSpace` with loop blocks). ``p``
does not depend on ``q`` at the same sample, so each step is explicit.

:func:`loop_simulate` evaluates the blocks it can compile (:func:`block_value`):
polynomials and two-segment polynomials, continued along their tangent beyond the range
``[lo, hi]`` their argument covered in estimation, and piecewise-linear maps (dead
zone, saturation, piecewise-linear, as breakpoints, values and end slopes).

:func:`loop_sensitivity` walks the sensitivities forward once a simulation has fixed
the trajectory: with the blocks' slopes ``φ'(p(k))`` and their parameters' effects
``∂φ/∂θ_φ`` known arrays (the model evaluates them on the whole piece at once), the
sensitivity of the state to every parameter obeys the linear recursion

.. math::

    \\partial p = C_p\\, \\partial x + D_p\\, \\partial w + [\\partial C_p] x + [\\partial D_p] w,
    \\qquad \\partial q = \\varphi'(p)\\, \\partial p + \\partial_\\theta \\varphi,
    \\\\
    \\partial x(k+1) = A\\, \\partial x + [B, B_q] [\\partial w; \\partial q]
        + [\\partial A] x + [\\partial B_{all}] v + [\\partial e], \\qquad
    \\partial z = C\\, \\partial x + [D, D_q] [\\partial w; \\partial q]
        + [\\partial C] x + [\\partial D_{all}] v

with ``v = [w; q]`` and the bracketed terms present only for the entry's own column.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from blockid._kernels.feedback import table_value

__all__ = ["KIND_POLYNOMIAL", "KIND_TABLE", "KIND_TWO_SEGMENT", "block_value",
           "loop_sensitivity", "loop_simulate"]  # fmt: skip

#: Codes of the blocks the kernels evaluate; their coefficients packed as
#: ``[m, c_0 .. c_{m-1}]`` (polynomial, lowest power first), ``[m, f_0 .. f_{m-1},
#: p_0 .. p_{m-1}]`` (two-segment polynomial: ``f(s) + [s < 0] p(s)``) and ``[n,
#: breakpoints (n), values (n), slope_left, slope_right]`` (piecewise-linear).
KIND_POLYNOMIAL, KIND_TABLE, KIND_TWO_SEGMENT = 0, 1, 2


@njit(cache=True)
def _horner(c, start, m, s):
    """Value and slope of ``sum_i c[start + i] s^i`` (``m`` coefficients)."""
    v = 0.0
    d = 0.0
    for i in range(m - 1, -1, -1):
        d = d * s + v
        v = v * s + c[start + i]
    return v, d


@njit(cache=True)
def block_value(kind, c, lo, hi, s):
    """Block ``kind`` with packed coefficients ``c`` at ``s``; a polynomial continues
    along its tangent outside ``[lo, hi]`` (infinite bounds: never)."""
    if s != s:  # NaN (an exploding run) stays NaN
        return s
    if kind == KIND_TABLE:
        n = int(c[0])
        return table_value(c[1 : 1 + n], c[1 + n : 1 + 2 * n], c[1 + 2 * n], c[2 + 2 * n], s)
    e = s
    if e < lo:
        e = lo
    elif e > hi:
        e = hi
    m = int(c[0])
    v, d = _horner(c, 1, m, e)
    if kind == KIND_TWO_SEGMENT and e < 0.0:
        v2, d2 = _horner(c, 1 + m, m, e)
        v += v2
        d += d2
    return v + d * (s - e)


@njit(cache=True)
def _affine(M, x, N, v, r, n):
    """``M[r] x + N[r, :n] v[:n]``."""
    acc = 0.0
    for c in range(x.shape[0]):
        acc += M[r, c] * x[c]
    for i in range(n):
        acc += N[r, i] * v[i]
    return acc


@njit(cache=True, nogil=True)
def loop_simulate(A, B, C, D, e, Cp, Dp, kinds, coef, ptr, lo, hi, w, x, X, P, Q, z):
    """Free run from ``x`` (updated in place to the state after the last sample).

    ``B`` (nx, nu + nl) and ``D`` (ny, nu + nl) hold the input and the loop columns;
    block ``l`` is ``kinds[l]`` with coefficients ``coef[ptr[l]:ptr[l + 1]]``. Writes
    the states before each update ``X`` (N, nx), the blocks' arguments ``P`` and
    outputs ``Q`` (N, nl) and the core's outputs ``z`` (N, ny)."""
    N, nu = w.shape[0], w.shape[1]
    nx, ny, nl = A.shape[0], C.shape[0], Cp.shape[0]
    nv = nu + nl
    v = np.empty(nv)
    xn = np.empty(nx)
    for k in range(N):
        for i in range(nu):
            v[i] = w[k, i]
        for r in range(nx):
            X[k, r] = x[r]
        for l in range(nl):
            acc = _affine(Cp, x, Dp, v, l, nu)
            P[k, l] = acc
            q = block_value(kinds[l], coef[ptr[l] : ptr[l + 1]], lo[l], hi[l], acc)
            Q[k, l] = q
            v[nu + l] = q
        for j in range(ny):
            z[k, j] = _affine(C, x, D, v, j, nv)
        for r in range(nx):
            xn[r] = e[r] + _affine(A, x, B, v, r, nv)
        for r in range(nx):
            x[r] = xn[r]


@njit(cache=True)
def _product(M, S, out, add):
    """``out (+)= M @ S`` (rows of ``M``; the sum over its columns in order, the
    columns of ``S`` innermost)."""
    for r in range(M.shape[0]):
        if not add:
            for j in range(S.shape[1]):
                out[r, j] = 0.0
        for c in range(M.shape[1]):
            m = M[r, c]
            for j in range(S.shape[1]):
                out[r, j] += m * S[c, j]


@njit(cache=True, nogil=True)
def loop_sensitivity(A, B, C, D, Cp, Dp, X, V, slope, Gin, chin, Gl, chl, offsets, S, J):
    """Walk ``S = ∂x/∂[θ, x(0)]`` (nx, n_cols; updated in place) over a simulated
    piece and write ``J = ∂z/∂[θ, x(0)]`` (N * ny, n_cols; row ``k * ny + j``).

    ``X`` (N, nx) and ``V = [w, q]`` (N, nu + nl) are the simulated states and core
    inputs, ``slope`` (N, nl) the blocks' slopes ``φ'(p)``; ``Gin`` (N, p_in) and
    ``Gl`` (N, p_loop) the input and loop blocks' parameter effects on their outputs,
    column ``j`` acting on channel ``chin[j]`` (``chl[j]``). ``offsets`` gives where
    each group of columns starts: ``[B, C, D, e, C_p, D_p, input blocks, loop blocks,
    x(0)]``; columns before ``B`` are ``A`` (row-major, like every matrix here) and the
    core's unused ``F`` lies between ``e`` and ``C_p``. Every column at once, the
    columns innermost: matrix products, then each entry's own term."""
    N = X.shape[0]
    nx, ny, nl = A.shape[0], C.shape[0], Cp.shape[0]
    nv = V.shape[1]
    nu = nv - nl
    oB, oC, oD, oE, oCp, oDp, oIn, oLoop = (
        offsets[0], offsets[1], offsets[2], offsets[3], offsets[4], offsets[5], offsets[6],
        offsets[7],
    )  # fmt: skip
    ncol = S.shape[1]
    Sn = np.empty((nx, ncol))
    dV = np.zeros((nv, ncol))
    dP = np.empty((nl, ncol))
    Jk = np.empty((ny, ncol))
    Bw, Bq, Dw, Dq = B[:, :nu], B[:, nu:], D[:, :nu], D[:, nu:]
    for k in range(N):
        dV[:, :] = 0.0
        for j in range(oLoop - oIn):
            dV[chin[j], oIn + j] = Gin[k, j]
        _product(Cp, S, dP, False)
        _product(Dp, dV[:nu], dP, True)
        for idx in range(nl * nx):
            dP[idx // nx, oCp + idx] += X[k, idx % nx]
        for idx in range(nl * nu):
            dP[idx // nu, oDp + idx] += V[k, idx % nu]
        for l in range(nl):
            s = slope[k, l]
            for j in range(ncol):
                dV[nu + l, j] = s * dP[l, j]
        for j in range(Gl.shape[1]):
            dV[nu + chl[j], oLoop + j] += Gl[k, j]
        _product(C, S, Jk, False)
        _product(Dw, dV[:nu], Jk, True)
        _product(Dq, dV[nu:], Jk, True)
        for idx in range(ny * nx):
            Jk[idx // nx, oC + idx] += X[k, idx % nx]
        for idx in range(ny * nv):
            Jk[idx // nv, oD + idx] += V[k, idx % nv]
        for r in range(ny):
            for j in range(ncol):
                J[k * ny + r, j] = Jk[r, j]
        _product(A, S, Sn, False)
        _product(Bw, dV[:nu], Sn, True)
        _product(Bq, dV[nu:], Sn, True)
        for idx in range(nx * nx):
            Sn[idx // nx, idx] += X[k, idx % nx]
        for idx in range(nx * nv):
            Sn[idx // nv, oB + idx] += V[k, idx % nv]
        for r in range(nx):
            Sn[r, oE + r] += 1.0
        for r in range(nx):
            for j in range(ncol):
                S[r, j] = Sn[r, j]
