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

**The walk in passes, on every core.** The columns of ``S`` are independent given the
state trajectory: each is the response of the same time-varying linear system
``(A + E ∂ζ/∂x, C + F ∂ζ/∂x)`` to its own explicit term. :func:`pnlss_trajectory`
runs the model over a piece once and keeps, per sample, ``v(k) = [x(k); u(k); ζ(k)]``
(the only sequential part); :func:`pnlss_local_jacobians` forms the two local
Jacobians of every sample, fixed blocks of samples in parallel, and
:func:`pnlss_sensitivities` walks fixed blocks of ``COLUMN_BLOCK`` columns in parallel
(``prange``). A small model's passes run on the calling thread instead (the
trajectory and local Jacobians in one pass, :func:`pnlss_trajectory_jacobians`, and
:func:`pnlss_sensitivities_serial`; the same arithmetic: :func:`pnlss_walk` chooses by
size), where starting a parallel region would cost more than the work. A parameter's
column is described by its kind (``STATE``: it enters row ``row`` of the state
equation as ``v_src``; ``OUTPUT``: row ``row`` of the output equation; ``INITIAL``: an
initial state, no explicit term), so a caller asks for exactly the columns it fits, in
its order. Each column's arithmetic is the same, in the
same order, whichever thread walks it and however many there are: the result does not
depend on the number of threads, bit for bit, and equals that of the one-pass walk of
the equations above, sample by sample (its slow twin in the tests' ``reference.py``).
A column of the output equation alone (``C``, ``D``, ``F``) never moves the state: while
its state sensitivity is zero (as every walk starts it) its sensitivity is its explicit
term, with no walk; one handed a nonzero start is walked like the others.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange

__all__ = [
    "COLUMN_BLOCK",
    "INITIAL",
    "OUTPUT",
    "STATE",
    "channel_response",
    "monomials",
    "SAMPLE_BLOCK",
    "pnlss_columns",
    "pnlss_local_jacobians",
    "pnlss_sensitivities",
    "pnlss_sensitivities_serial",
    "pnlss_simulate",
    "pnlss_trajectory",
    "pnlss_trajectory_jacobians",
    "pnlss_walk",
]

#: Kinds of a parameter's column in :func:`pnlss_sensitivities`.
STATE, OUTPUT, INITIAL = 0, 1, 2
#: Columns walked together by one thread: a fixed partition (not one per thread), so
#: the result is the same with any number of threads. A walk of one block runs on the
#: calling thread (:func:`pnlss_sensitivities_serial`).
COLUMN_BLOCK = 128
#: Below this ``(nx + ny) (nx + nm)`` (the local Jacobians' size, a measure of their
#: work per sample) :func:`pnlss_walk` forms them on the calling thread: starting a
#: parallel region costs more than a small model's samples (measured: docs/performance.md).
LOCAL_PARALLEL_WORK = 64


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


@njit(cache=True, nogil=True)
def _stack(x, u, z):
    """``z = [x; u]``: the variables of the monomials at one sample."""
    nx = x.shape[0]
    for i in range(nx):
        z[i] = x[i]
    for i in range(u.shape[0]):
        z[nx + i] = u[i]


@njit(cache=True, nogil=True)
def _affine(M, N, P, x, u, zeta, out):
    """``out = M x + N u + P ζ``: one equation of the model at one sample (the state's
    with ``A, B, E``, the output's with ``C, D, F``), each row's terms added in that
    order."""
    for i in range(M.shape[0]):
        acc = 0.0
        for j in range(x.shape[0]):
            acc += M[i, j] * x[j]
        for j in range(u.shape[0]):
            acc += N[i, j] * u[j]
        for j in range(zeta.shape[0]):
            acc += P[i, j] * zeta[j]
        out[i] = acc


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
    nx, nu, nm = A.shape[0], B.shape[1], expo.shape[0]
    count, var, power = _sparse_exponents(expo)
    top = _powers(count, var, power, nm)
    z = np.empty(nx + nu)
    zp = np.empty((nx + nu, top + 1))  # each variable's powers, as monomials() takes them
    zeta = np.empty(nm)
    xn = np.empty(nx)
    for k in range(N):
        _stack(x, u[k], z)
        for i in range(nx + nu):
            _power_row(min(max(z[i], lo[i]), hi[i]), top, zp[i])
        for j in range(nm):  # monomials(z, ...): each one's powers in ascending variable
            val = 1.0
            for t in range(count[j]):
                val *= zp[var[j, t], power[j, t]]
            zeta[j] = val
        _affine(C, D, F, x, u[k], zeta, y[k])
        _affine(A, B, E, x, u[k], zeta, xn)
        finite = True
        for i in range(nx):
            if not np.isfinite(xn[i]):
                finite = False
        if not finite:
            y[k + 1 :, :] = np.nan
            return False
        for i in range(nx):
            x[i] = xn[i]
    return True


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


@njit(cache=True, nogil=True)
def _sparse_exponents(expo):
    """Each monomial's variables and powers (``count[j]`` of them, ascending variable):
    the monomials of a few variables each, without a pass over all ``nx + nu``."""
    nm, nz = expo.shape
    count = np.zeros(nm, dtype=np.int64)
    var = np.zeros((nm, nz), dtype=np.int64)
    power = np.zeros((nm, nz), dtype=np.int64)
    for j in range(nm):
        for i in range(nz):
            if expo[j, i]:
                var[j, count[j]] = i
                power[j, count[j]] = expo[j, i]
                count[j] += 1
    return count, var, power


@njit(cache=True, nogil=True)
def _powers(count, var, power, nm):
    """The largest power any monomial takes of one variable."""
    top = 0
    for j in range(nm):
        for t in range(count[j]):
            top = max(top, power[j, t])
    return top


@njit(cache=True, nogil=True)
def _power_row(zi, top, row):
    """``row[e] = zi ** e`` for ``e = 0 .. top``: the powers 0 and 1 as they are
    (``zi ** 0`` is 1 and ``zi ** 1`` is ``zi`` exactly), the others by ``**`` as
    :func:`monomials` takes them, so every monomial is the same number."""
    row[0] = 1.0
    if top >= 1:
        row[1] = zi
    for e in range(2, top + 1):
        row[e] = zi**e


@njit(cache=True, nogil=True)
def pnlss_trajectory(A, B, C, D, E, F, expo, lo, hi, u, x, y, V):
    """The free run over a piece, keeping ``V[k] = [x(k); u(k); ζ(k)]`` per sample
    ``k`` (the sequential part of the walk: :func:`pnlss_local_jacobians` then works on
    every sample at once). ``x`` is updated in place to the state after the last sample;
    ``y`` (N, ny) receives the output."""
    none = np.empty((0, 0, 0))
    _run_keeping(A, B, C, D, E, F, expo, lo, hi, u, x, y, V, none, none, False)


@njit(cache=True, nogil=True)
def pnlss_trajectory_jacobians(A, B, C, D, E, F, expo, lo, hi, u, x, y, V, JX, JY):
    """:func:`pnlss_trajectory` and :func:`pnlss_local_jacobians` in one pass on the
    calling thread (a small model's walk: each sample's Jacobians from the powers the
    free run has just taken; the same numbers as the two passes)."""
    _run_keeping(A, B, C, D, E, F, expo, lo, hi, u, x, y, V, JX, JY, True)


@njit(cache=True, nogil=True)
def _run_keeping(A, B, C, D, E, F, expo, lo, hi, u, x, y, V, JX, JY, jacobians):
    """The free run keeping ``V``; with ``jacobians``, each sample's local Jacobians
    into ``JX``, ``JY`` as it goes."""
    N = u.shape[0]
    nx, nu, nm = A.shape[0], B.shape[1], expo.shape[0]
    count, var, power = _sparse_exponents(expo)
    top = _powers(count, var, power, nm)
    z = np.empty(nx + nu)
    zp = np.empty((nx + nu, top + 1))  # zp[i, e] = clip(z_i) ** e (the same power)
    zeta = np.empty(nm)
    xn = np.empty(nx)
    At, Ct, Et, Ft = _transposed(A, C, E, F)
    Lx, Ly = np.empty((nx, nx)), np.empty((nx, C.shape[0]))
    for k in range(N):
        _stack(x, u[k], z)
        for i in range(nx + nu):
            _power_row(min(max(z[i], lo[i]), hi[i]), top, zp[i])
            V[k, i] = z[i]
        for j in range(nm):
            val = 1.0
            for t in range(count[j]):
                val *= zp[var[j, t], power[j, t]]
            zeta[j] = val
            V[k, nx + nu + j] = val
        if jacobians:
            _local_sample(At, Ct, Et, Ft, count, var, power, lo, hi, V, zp, Lx, Ly, JX, JY, k)
        _affine(C, D, F, x, u[k], zeta, y[k])
        _affine(A, B, E, x, u[k], zeta, xn)
        for i in range(nx):
            x[i] = xn[i]


#: Samples per task of :func:`pnlss_local_jacobians` (each sample's Jacobians stand alone).
SAMPLE_BLOCK = 256


@njit(cache=True, nogil=True)
def _local_block(A, C, E, F, count, var, power, top, lo, hi, V, JX, JY, k0, k1):
    """:func:`pnlss_local_jacobians` over samples ``k0:k1`` (one task)."""
    nx, ny = A.shape[0], C.shape[0]
    nz = V.shape[1] - count.shape[0]
    zp = np.empty((nz, top + 1))
    At, Ct, Et, Ft = _transposed(A, C, E, F)
    Lx, Ly = np.empty((nx, nx)), np.empty((nx, ny))
    for k in range(k0, k1):
        for i in range(nz):
            _power_row(min(max(V[k, i], lo[i]), hi[i]), top, zp[i])
        _local_sample(At, Ct, Et, Ft, count, var, power, lo, hi, V, zp, Lx, Ly, JX, JY, k)


@njit(cache=True, nogil=True)
def _transposed(A, C, E, F):
    """``A, C, E, F`` transposed, contiguous: the local Jacobians add a monomial's
    column of ``E`` (``F``) into a column of ``JX`` (``JY``), contiguous this way."""
    return A.T.copy(), C.T.copy(), E.T.copy(), F.T.copy()


@njit(cache=True, nogil=True)
def _local_sample(At, Ct, Et, Ft, count, var, power, lo, hi, V, zp, Lx, Ly, JX, JY, k):
    """The local Jacobians of sample ``k`` from its row of ``V`` and its variables'
    clipped powers ``zp``: built transposed in ``Lx`` (nx, nx) and ``Ly`` (nx, ny) from
    the transposed matrices (:func:`_transposed`), then written to ``JX[k]``, ``JY[k]``;
    each entry's terms added in the same order as into ``JX`` itself."""
    nx, ny, nm = At.shape[0], Ct.shape[1], count.shape[0]
    for i in range(nx):
        for r in range(nx):
            Lx[i, r] = At[i, r]
        for r in range(ny):
            Ly[i, r] = Ct[i, r]
    for m in range(nm):
        for t in range(count[m]):
            i = var[m, t]
            if i >= nx or not (lo[i] < V[k, i] < hi[i]):
                continue
            p = power[m, t]
            d = p * zp[i, p - 1]  # z_i is inside its range: clip(z_i) = z_i
            for t2 in range(count[m]):
                if t2 != t:
                    d *= zp[var[m, t2], power[m, t2]]
            for r in range(nx):
                Lx[i, r] += Et[m, r] * d
            for r in range(ny):
                Ly[i, r] += Ft[m, r] * d
    for r in range(nx):
        for i in range(nx):
            JX[k, r, i] = Lx[i, r]
    for r in range(ny):
        for i in range(nx):
            JY[k, r, i] = Ly[i, r]


@njit(cache=True, nogil=True, parallel=True)
def pnlss_local_jacobians(A, C, E, F, expo, lo, hi, V, JX, JY):
    """``JX[k] = A + E ∂ζ/∂x`` and ``JY[k] = C + F ∂ζ/∂x`` at every sample of a
    trajectory (:func:`pnlss_trajectory`'s ``V``), blocks of ``SAMPLE_BLOCK`` samples on
    numba's threads; a clipped coordinate has zero slope. Each monomial's own variables
    only, the terms added monomial by monomial in ascending order (the dense sums'
    order, their zero terms left out: the same numbers)."""
    N = V.shape[0]
    count, var, power = _sparse_exponents(expo)
    top = _powers(count, var, power, expo.shape[0])
    blocks = (N + SAMPLE_BLOCK - 1) // SAMPLE_BLOCK
    for b in prange(blocks):
        k1 = min(N, (b + 1) * SAMPLE_BLOCK)
        _local_block(A, C, E, F, count, var, power, top, lo, hi, V, JX, JY, b * SAMPLE_BLOCK, k1)


@njit(cache=True, nogil=True)
def _combine(c, Sb, out, n):
    """``out[t] = 0 + c[0] Sb[0, t] + c[1] Sb[1, t] + ...`` for ``t < n``, the terms added
    in that order (the same number as a running sum), two rows of ``Sb`` per pass over
    ``out`` (half the loads and stores of one row at a time)."""
    m = c.shape[0]
    if m % 2:
        a = c[0]
        for t in range(n):
            out[t] = 0.0 + a * Sb[0, t]
        j = 1
    else:
        a, b = c[0], c[1]
        for t in range(n):
            out[t] = (0.0 + a * Sb[0, t]) + b * Sb[1, t]
        j = 2
    while j < m:
        a, b = c[j], c[j + 1]
        for t in range(n):
            out[t] = (out[t] + a * Sb[j, t]) + b * Sb[j + 1, t]
        j += 2


@njit(cache=True, nogil=True)
def _walk_block(V, JX, JY, kind, row, src, S, J, c0, c1):
    """Columns ``c0:c1`` of :func:`pnlss_sensitivities` (one thread's block): the
    columns that move the state (every one but an output equation's whose state
    sensitivity is zero) walked in two local buffers, each output row summed in a third,
    the innermost loops over those columns (vectorised); the others get their explicit
    terms alone. The explicit terms are added from lists made once per block, not by a
    test of every column at every sample."""
    N, ny, nx = JY.shape
    w = c1 - c0
    moving = np.empty(w, dtype=np.int64)
    still = np.empty(w, dtype=np.int64)
    n_moving, n_still = 0, 0
    for q in range(w):
        moves = kind[c0 + q] != OUTPUT
        for j in range(nx):
            if S[j, c0 + q] != 0.0:
                moves = True
        if moves:
            moving[n_moving] = q
            n_moving += 1
        else:
            still[n_still] = q
            n_still += 1
    if n_moving == 0:  # the output equation's columns alone: their explicit terms
        for k in range(N):
            for i in range(ny):
                for q in range(w):
                    p = c0 + q
                    J[k * ny + i, p] = V[k, src[p]] if row[p] == i else 0.0
        return
    # explicit terms of the moving columns: (their place among them, row, source)
    terms = np.empty((6, n_moving), dtype=np.int64)
    out_t, out_row, out_src = terms[0], terms[1], terms[2]
    st_t, st_row, st_src = terms[3], terms[4], terms[5]
    n_out, n_st = 0, 0
    for t in range(n_moving):
        p = c0 + moving[t]
        if kind[p] == OUTPUT:
            out_t[n_out], out_row[n_out], out_src[n_out] = t, row[p], src[p]
            n_out += 1
        elif kind[p] == STATE:
            st_t[n_st], st_row[n_st], st_src[n_st] = t, row[p], src[p]
            n_st += 1
    Sb = np.empty((nx, n_moving))
    Sn = np.empty((nx, n_moving))
    acc = np.empty(n_moving)
    for j in range(nx):
        for t in range(n_moving):
            Sb[j, t] = S[j, c0 + moving[t]]
    for k in range(N):
        for i in range(ny):
            r = k * ny + i
            _combine(JY[k, i], Sb, acc, n_moving)
            for e in range(n_out):
                if out_row[e] == i:
                    acc[out_t[e]] += V[k, out_src[e]]
            for t in range(n_moving):
                J[r, c0 + moving[t]] = acc[t]
            for e in range(n_still):  # a zero sensitivity: 0 + the explicit term, as walked
                p = c0 + still[e]
                J[r, p] = 0.0 + V[k, src[p]] if row[p] == i else 0.0
        for i in range(nx):
            _combine(JX[k, i], Sb, Sn[i], n_moving)
        for e in range(n_st):
            Sn[st_row[e], st_t[e]] += V[k, st_src[e]]
        Sb, Sn = Sn, Sb
    for j in range(nx):
        for t in range(n_moving):
            S[j, c0 + moving[t]] = Sb[j, t]


@njit(cache=True, nogil=True, parallel=True)
def pnlss_sensitivities(V, JX, JY, kind, row, src, S, J):
    """The output sensitivities of a piece from its trajectory (:func:`pnlss_trajectory`),
    fixed blocks of ``COLUMN_BLOCK`` columns on the threads numba has.

    Column ``p`` is the parameter of kind ``kind[p]`` (:data:`STATE`, :data:`OUTPUT`,
    :data:`INITIAL`) entering row ``row[p]`` of its equation as ``V[:, src[p]]``.
    ``S`` (nx, P) carries the state sensitivities across pieces, in place (start: 0, and
    the unit vector ``e_j`` for the initial state ``x_j(0)``); row ``k * ny + i`` of ``J``
    (N ny, P) receives ``∂y_i(k)/∂θ_p``.
    """
    P = S.shape[1]
    blocks = (P + COLUMN_BLOCK - 1) // COLUMN_BLOCK
    for b in prange(blocks):
        c0 = b * COLUMN_BLOCK
        _walk_block(V, JX, JY, kind, row, src, S, J, c0, min(P, c0 + COLUMN_BLOCK))


@njit(cache=True, nogil=True)
def pnlss_sensitivities_serial(V, JX, JY, kind, row, src, S, J):
    """:func:`pnlss_sensitivities` on the calling thread, block after block: the same
    numbers (one block's columns never meet another's)."""
    P = S.shape[1]
    for c0 in range(0, P, COLUMN_BLOCK):
        _walk_block(V, JX, JY, kind, row, src, S, J, c0, min(P, c0 + COLUMN_BLOCK))


def pnlss_columns(nx: int, nu: int, ny: int, nm: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(kind, row, src)`` of every column of ``[A, B, C, D, E, F, x(0)]`` (each matrix
    row-major, the order of the models' free parameters); a caller selects the ones it
    fits."""
    kind, row, src = [], [], []
    for rows, cols, k, first in ((nx, nx, STATE, 0), (nx, nu, STATE, nx), (ny, nx, OUTPUT, 0),
                                 (ny, nu, OUTPUT, nx), (nx, nm, STATE, nx + nu),
                                 (ny, nm, OUTPUT, nx + nu)):  # fmt: skip
        for i in range(rows):
            for j in range(cols):
                kind.append(k)
                row.append(i)
                src.append(first + j)
    for j in range(nx):
        kind.append(INITIAL)
        row.append(j)
        src.append(0)
    return (np.array(kind, dtype=np.int64), np.array(row, dtype=np.int64),
            np.array(src, dtype=np.int64))  # fmt: skip


def pnlss_walk(A, B, C, D, E, F, expo, lo, hi, u, x, S, y, J, columns=None):
    """Free run and ``∂y/∂[θ, x(0)]`` over a piece of a record, carrying the state: the
    passes (:func:`pnlss_trajectory`, then :func:`pnlss_local_jacobians` and
    :func:`pnlss_sensitivities` on numba's threads).

    ``x`` (nx,) and ``S`` (nx, P) hold the state and its sensitivity at the piece's
    first sample and are updated in place to those after its last (start with ``S`` 0
    but 1 at the initial states' own entries). Row ``k * ny + i`` of ``J`` (N ny, P)
    receives ``∂y_i(k)/∂θ_p``; ``y`` (N, ny) the output. ``columns`` ``(kind, row,
    src)`` names the columns of ``S`` and ``J`` (default: all of :func:`pnlss_columns`,
    in its order)."""
    n = u.shape[0]
    nx, nu, ny, nm = A.shape[0], B.shape[1], C.shape[0], expo.shape[0]
    if columns is None:
        columns = pnlss_columns(nx, nu, ny, nm)
    V = np.empty((n, nx + nu + nm))
    JX = np.empty((n, nx, nx))
    JY = np.empty((n, ny, nx))
    threads = numba.get_num_threads() > 1
    if threads and (nx + ny) * (nx + nm) >= LOCAL_PARALLEL_WORK:
        pnlss_trajectory(A, B, C, D, E, F, expo, lo, hi, u, x, y, V)
        pnlss_local_jacobians(A, C, E, F, expo, lo, hi, V, JX, JY)
    else:
        pnlss_trajectory_jacobians(A, B, C, D, E, F, expo, lo, hi, u, x, y, V, JX, JY)
    if threads and S.shape[1] > COLUMN_BLOCK:
        pnlss_sensitivities(V, JX, JY, *columns, S, J)
    else:
        pnlss_sensitivities_serial(V, JX, JY, *columns, S, J)
