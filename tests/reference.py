"""Slow, obviously-correct twins of the compiled kernels (the stumpy ``naive.py`` idea).

Written in the textbook form of SPEC.md with plain NumPy, one sample at a time. Also the
small models and records that several test files share (imported as ``from reference
import ...``).
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math

import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from blockid._kernels.state_space import monomials
from blockid.blocks import (
    DeadZone,
    Polynomial,
    TwoSegmentPolynomial,
)
from blockid.blocks.base import StaticBlock
from blockid.data import Dataset
from blockid.models import (
    ARX,
    Hammerstein,
    HammersteinWiener,
)
from blockid.models.state_space import StateSpace
from blockid.plants.electrohydraulic import (
    ElectrohydraulicParameters,
)
from blockid.workflows.effort import Effort


def rls(Phi, Y, lam, mu, theta0=0.0, trace_max=np.inf):
    """Textbook RLS (A2) with the trace bound of blockid applied when lambda < 1."""
    N, n = Phi.shape
    Y = Y.reshape(N, -1)
    theta = np.full((n, Y.shape[1]), theta0, dtype=float)
    P = mu * np.eye(n)
    for t in range(N):
        phi = Phi[t][:, None]
        K = P @ phi / (lam[t] + (phi.T @ P @ phi).item())
        e = Y[t] - (phi.T @ theta)[0]
        theta = theta + K @ e[None, :]
        P = (P - K @ phi.T @ P) / lam[t]
        if lam[t] < 1.0 and np.trace(P) > trace_max:
            P *= trace_max / np.trace(P)
    return theta, P


def aw_rls(Phi, Y, eps1, eps2, mu, theta0=0.01):
    """Adaptive-weighted RLS (A8), returning the weights lambda(t) too."""
    N, n = Phi.shape
    Y = Y.reshape(N, -1)
    theta = np.full((n, Y.shape[1]), theta0, dtype=float)
    P = mu * np.eye(n)
    weights = np.empty(N)
    for t in range(N):
        phi = Phi[t][:, None]
        s = (phi.T @ P @ phi).item()
        weights[t] = eps1 * s + eps2
        e = Y[t] - (phi.T @ theta)[0]
        theta = theta + P @ phi @ e[None, :] / (weights[t] + s)
        P = P - P @ phi @ phi.T @ P / (weights[t] + s)
    return theta, P, weights


def hierarchical_rls(Phi, Y, groups, lam, mu, theta0=0.0):
    """H-RLS (A10) for any grouping of the columns (lists of indices)."""
    N, n = Phi.shape
    Y = Y.reshape(N, -1)
    theta = np.full((n, Y.shape[1]), theta0, dtype=float)
    Ps = [mu * np.eye(len(g)) for g in groups]
    for t in range(N):
        e = Y[t] - Phi[t] @ theta
        for gi, g in enumerate(groups):
            phi = Phi[t, g][:, None]
            P = Ps[gi]
            denom = lam[t] + (phi.T @ P @ phi).item()
            theta[g] = theta[g] + (P @ phi / denom) @ e[None, :]
            Ps[gi] = (P - P @ phi @ phi.T @ P / denom) / lam[t]
    return theta, Ps


def weighted_least_squares(Phi, Y, weights, prior_weight=0.0, theta0=0.0):
    """argmin sum_t w_t |y_t - Phi_t theta|^2 + prior_weight |theta - theta0|^2, exactly."""
    n = Phi.shape[1]
    Y = Y.reshape(Phi.shape[0], -1)
    A = Phi.T @ (weights[:, None] * Phi) + prior_weight * np.eye(n)
    b = Phi.T @ (weights[:, None] * Y) + prior_weight * theta0
    return np.linalg.solve(A, b)


def tito_arx(inputs=("v1", "v2"), outputs=("y1", "y2"), **kwargs):
    """The stable two-input two-output ARX used across the tests (paper A's flow-field
    orders: na = 2 own and cross lags, nb = 2, nk = 1)."""
    from blockid.models import ARX

    (i1, i2), (o1, o2) = inputs, outputs
    return ARX(
        list(inputs),
        list(outputs),
        na=2,
        nb=2,
        nk=1,
        a={o1: {o1: [-1.2, 0.4], o2: [0.1, 0.0]}, o2: {o1: [0.05, 0.02], o2: [-0.9, 0.2]}},
        b={o1: {i1: [0.5, 0.2], i2: [0.1, -0.05]}, o2: {i1: [0.0, 0.03], i2: [0.4, 0.1]}},
        **kwargs,
    )


class TanhSpring(StaticBlock):
    """A user's block that the compiled kernels do not know: ``N(y) = k tanh(y)``."""

    kind = "test-tanh-spring"

    def __init__(self, k: float) -> None:
        self.k = float(k)

    @property
    def parameters(self):
        return {"k": self.k}

    def __call__(self, u):
        return self.k * np.tanh(np.asarray(u, dtype=float))


def squared_state_record(n=1500, seed=0, noise=0.01):
    """A second-order plant whose nonlinearity acts on its state (``0.3 x1^2`` fed into
    ``x2``), driven by uniform noise, with white output noise: a record that one static
    block around one linear block cannot model and a polynomial state-space model can."""
    from blockid.data import Dataset

    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    x, y = np.zeros(2), np.zeros(n)
    for k in range(n):
        y[k] = x[0]
        x = np.array([0.6 * x[0] + 0.3 * x[1] + u[k], -0.2 * x[0] + 0.5 * x[1] + 0.3 * x[0] ** 2])
    return Dataset.from_arrays(u, y + noise * rng.standard_normal(n), ["u"], ["y"])


def cubic_state_record(n=1500, seed=0, noise=0.01):
    """A second-order plant whose first state is fed back through ``-0.15 x1^3``
    (an odd nonlinearity: no monomial of degree 2 holds it), uniform input, white output
    noise: a polynomial state-space model needs degree 3."""
    from blockid.data import Dataset

    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    x, y = np.zeros(2), np.zeros(n)
    for k in range(n):
        y[k] = x[0] + 0.4 * x[1]
        x = np.array([1.2 * x[0] - 0.35 * x[1] + u[k] - 0.15 * x[0] ** 3, x[0]])
    return Dataset.from_arrays(u, y + noise * rng.standard_normal(n), ["u"], ["y"])


# Records and models shared by tests found by mutation testing (docs/testing.md)
#: A two-input two-output Hammerstein-Wiener plant on a third-order state-space core:
#: input cubics with unit linear coefficient and no constant, output cubics likewise
#: (coefficients lowest power first).
MIMO_HW_INPUT = [[0.0, 1.0, 0.0, 0.3], [0.0, 1.0, 0.4, 0.0]]
MIMO_HW_OUTPUT = [[0.0, 1.0, 0.2, -0.05], [0.0, 1.0, -0.1, 0.0]]


def mimo_hw_plant():
    from blockid.models.block_state_space import BlockStateSpace

    return BlockStateSpace(
        ["u1", "u2"], ["y1", "y2"],
        A=[[0.7, 0.2, 0.0], [-0.2, 0.7, 0.0], [0.0, 0.0, 0.5]],
        B=[[1.0, 0.0], [0.0, 0.5], [0.3, 1.0]],
        C=[[1.0, 0.0, 0.5], [0.0, 1.0, 1.0]],
        D=np.zeros((2, 2)),
        input_blocks=[Polynomial(c) for c in MIMO_HW_INPUT],
        output_blocks=[Polynomial(c[1:], constant=False) for c in MIMO_HW_OUTPUT],
    )  # fmt: skip


def mimo_hw_record(n=4000, snr_db=40.0, seed=1):
    """``(data, u)``: the plant driven by uniform white inputs on [-1.5, 1.5], white
    output noise at ``snr_db``."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.5, 1.5, (n, 2))
    y = mimo_hw_plant().simulate(u)
    y = y + rng.standard_normal(y.shape) * y.std(axis=0) * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, inputs=["u1", "u2"], outputs=["y1", "y2"]), u


def mimo_loop_plant(kind):
    """A plant of two inputs and two outputs with a static block in each of two loops
    (:class:`~blockid.models.block_state_space.BlockStateSpace` loop blocks):

    * ``"lure"``: two coupled second-order channels, each output fed back through a
      saturation (knees -0.4/0.4 and -0.3/0.5), a multivariable Lur'e system;
    * ``"wiener-hammerstein"``: two paths, each a first-order filter of both inputs, a
      dead zone (edges -0.3/0.2 and -0.2/0.4) and a second first-order filter (beside
      a linear path from the first filter's state).
    """
    from blockid.blocks import DeadZone, Saturation
    from blockid.models.block_state_space import BlockStateSpace

    if kind == "lure":
        A = 0.9 * np.array([[1.2, -0.5, 0, 0], [1, 0, 0, 0], [0, 0, 0.9, -0.3], [0, 0, 1, 0]])
        B = [[1, 0.3], [0, 0], [0.2, 1], [0, 0]]
        C = np.array([[0.5, 0.3, 0, 0], [0, 0, 0.6, 0.2]])
        blocks, Cp = [Saturation(-0.4, 0.4), Saturation(-0.3, 0.5)], C
        Bq = [[-0.8, 0], [0, 0], [0, -0.7], [0, 0]]
    else:
        A = np.diag([0.6, 0.8, 0.5, 0.7])
        A[1, 0], A[3, 2] = 0.5, 0.4
        B = [[1, 0.4], [0, 0], [0.3, 1], [0, 0]]
        C = 0.5 * np.array([[0, 1, 0, 0], [0, 0, 0, 1]])
        blocks, Cp = [DeadZone(-0.3, 0.2), DeadZone(-0.2, 0.4)], [[1, 0, 0, 0], [0, 0, 1, 0]]
        Bq = [[0, 0], [1, 0], [0, 0], [0, 1]]
    return BlockStateSpace(
        ["u1", "u2"], ["y1", "y2"], A, B, C, np.zeros((2, 2)), loop_blocks=blocks, Cp=Cp,
        Dp=np.zeros((2, 2)), Bq=Bq, Dq=np.zeros((2, 2)),
    )  # fmt: skip


def mimo_loop_record(kind, n=2000, snr_db=40.0, seed=1):
    """``(data, u, y_true)``: :func:`mimo_loop_plant` driven by uniform white inputs on
    [-1.5, 1.5]; white output noise at ``snr_db``."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.5, 1.5, (n, 2))
    y_true = mimo_loop_plant(kind).simulate(u)
    y = y_true + rng.standard_normal(y_true.shape) * y_true.std(axis=0) * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, inputs=["u1", "u2"], outputs=["y1", "y2"]), u, y_true


def tank_overflow_plant():
    """An upper tank (level ``x1``) that overflows, draining faster beyond level 0.8 (a
    dead zone of its state fed back: a static block on a state, not on the output),
    measured as the level of a second tank it fills: one input, one output."""
    from blockid.blocks import DeadZone
    from blockid.models.block_state_space import BlockStateSpace

    return BlockStateSpace(
        ["u"], ["y"], [[0.95, 0.0], [0.3, 0.85]], [[0.5], [0.0]], [[0.0, 1.0]], [[0.0]],
        loop_blocks=[DeadZone(-10.0, 0.8, 1e-9, 1.0)], Cp=[[1.0, 0.0]], Dp=[[0.0]],
        Bq=[[-0.6], [0.0]], Dq=[[0.0]],
    )  # fmt: skip


def tank_overflow_record(n=2000, snr_db=40.0, seed=1):
    """``(data, u, y_true)``: :func:`tank_overflow_plant` filled by a staircase of
    uniform levels on [0, 1] held 10 samples each, white output noise at ``snr_db``."""
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 1.0, n // 10 + 1), 10)[:n, None]
    y_true = tank_overflow_plant().simulate(u)
    y = y_true + rng.standard_normal(y_true.shape) * y_true.std() * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"]), u, y_true


def assert_shaped_follows_the_names(model):
    """``model.shaped`` puts each entry of :meth:`free_parameters` where its name in
    ``free_parameter_names`` says (``A[i,j]``, ``e[i]``, ``loop p1: lower`` under
    ``"loop block p1"``): fed the indices, every matrix entry, vector entry and block
    parameter holds the index of its own name, and no index appears twice."""
    names = model.free_parameter_names()
    out = model.shaped(np.arange(len(names), dtype=float))
    seen = []
    for key, value in out.items():
        if isinstance(value, dict):  # a block's parameters: "side block c" -> {name: k}
            side, _, channel = key.partition(" block ")
            for param, k in value.items():
                assert names[int(k)] == f"{side} {channel}: {param}"
                seen.append(int(k))
            continue
        for index, k in np.ndenumerate(np.asarray(value)):
            assert names[int(k)] == f"{key}[{','.join(map(str, index))}]", (key, index)
            seen.append(int(k))
    assert len(seen) == len(set(seen))
    return seen


def _arx_data(n=200, seed=0):
    # y(t) = 0.5 y(t-1) + u(t-1), noise free
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    y = np.zeros(n)
    for t in range(1, n):
        y[t] = 0.5 * y[t - 1] + u[t - 1]
    return u, y


def _dataset():
    u, y = _arx_data()
    return Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])


def _backlash_model(a=-0.5):
    # backlash (unit slopes, c = 0.3) then x(t) = -a x(t-1) + w(t-1)
    from blockid.blocks import Backlash
    from blockid.models import BacklashModel

    return BacklashModel(
        "u", "y", input_block=Backlash(1.0, 0.3, 1.0, 0.3), na=1, nb=1, nk=1, a=[a]
    )


def _backlash_data(scale=1.0):
    # the backlash model's output, noise free, times `scale`
    truth = _backlash_model()
    rng = np.random.default_rng(0)
    u = 2.0 * np.sin(np.linspace(0.0, 12.0 * np.pi, 400)) + 0.3 * rng.standard_normal(400)
    return truth, Dataset.from_arrays(u, scale * truth.simulate(u)[:, 0], ["u"], ["y"])


def _feedback(c, **kwargs):
    from blockid.blocks.linear import LinearBlock
    from blockid.models.feedback import LinearFeedback

    return LinearFeedback(
        "u",
        "y",
        linear=kwargs.pop("linear", LinearBlock(1, 1, 1, a=[-0.5], b=[1.0])),
        feedback=Polynomial(c, constant=False),
        **kwargs,
    )


def mimo_lure_record(n=3000, seed=1, noise=0.01):
    """A two-input two-output Lur'e plant: a coupled second-order core whose outputs are
    fed back through a cubic each (``x+ = A x + B u - F y**3``, ``y = x``), driven by
    held uniform inputs; estimation (first 2/3, output noise ``noise`` of each output's
    spread) and noise-free validation (last third) data sets."""
    A, B = np.array([[0.7, 0.2], [-0.1, 0.6]]), np.array([[1.0, 0.3], [0.2, 0.8]])
    F = np.diag([0.3, 0.25])
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, (n // 3, 2)), 3, axis=0)
    x, y = np.zeros(2), np.zeros((u.shape[0], 2))
    for k in range(u.shape[0]):
        y[k] = x
        x = A @ x + B @ u[k] - F @ y[k] ** 3
    return _two_parts(u, y, rng, noise)


def mimo_wiener_hammerstein_record(n=3000, seed=2, noise=0.01):
    """A two-input two-output Wiener-Hammerstein plant: a diagonal first linear block fed
    by both inputs, a static ``v + 0.3 v**3`` per channel, a coupled second linear block;
    estimation and validation sets as :func:`mimo_lure_record`."""
    A1, B1 = np.diag([0.6, 0.5]), np.array([[1.0, 0.4], [0.3, 1.0]])
    A2 = np.array([[0.5, 0.2], [0.0, 0.4]])
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, (n // 3, 2)), 3, axis=0)
    x1, x2, y = np.zeros(2), np.zeros(2), np.zeros((u.shape[0], 2))
    for k in range(u.shape[0]):
        y[k] = x2
        x1, x2 = A1 @ x1 + B1 @ u[k], A2 @ x2 + x1 + 0.3 * x1**3
    return _two_parts(u, y, rng, noise)


def _two_parts(u, y, rng, noise):
    from blockid.data import Dataset

    cut = 2 * u.shape[0] // 3
    noisy = y + noise * y.std(axis=0) * rng.standard_normal(y.shape)
    names = (["u1", "u2"], ["y1", "y2"])
    return Dataset.from_arrays(u[:cut], noisy[:cut], *names), Dataset.from_arrays(
        u[cut:], y[cut:], *names
    )


def mimo_orders_record(n=1500, seed=0, noise=0.02):
    """A 2-input 2-output ARX plant whose pairs need their own numbers of input
    coefficients: ``nb = [[2, 1], [0, 1]]`` at delay 1 (input 1 does not act on output
    2), held Gaussian inputs, white output noise (``noise``, absolute)."""
    from blockid.data import Dataset

    rng = np.random.default_rng(seed)
    u = np.repeat(rng.standard_normal((n // 3, 2)), 3, axis=0)
    y = np.zeros((n, 2))
    for t in range(3, n):
        y[t, 0] = (1.2 * y[t - 1, 0] - 0.4 * y[t - 2, 0] + 0.5 * u[t - 1, 0]
                   + 0.4 * u[t - 2, 0] + 0.3 * u[t - 1, 1])  # fmt: skip
        y[t, 1] = 0.6 * y[t - 1, 1] - 0.5 * u[t - 1, 1]
    y += noise * rng.standard_normal(y.shape)
    return Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"])


def mimo_delays_record(delays, n=1500, seed=0, noise=0.02):
    """A coupled 2-input 2-output ARX plant whose inputs act with their own delays
    (``delays[i][j]``: of input j in output i), driven by held Gaussian inputs, with
    white output noise (``noise``, absolute)."""
    from blockid.data import Dataset

    (a, b), (c, d) = delays
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.standard_normal((n // 3, 2)), 3, axis=0)
    y = np.zeros((n, 2))
    for t in range(10, n):
        y[t, 0] = 1.2 * y[t - 1, 0] - 0.4 * y[t - 2, 0] + 0.5 * u[t - a, 0] + 0.3 * u[t - b, 1]
        y[t, 1] = 0.6 * y[t - 1, 1] + 0.6 * u[t - c, 0] - 0.5 * u[t - d, 1]
    y += noise * rng.standard_normal(y.shape)
    return Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"])


# ----------------------------------------------------- polynomial state space, one pass
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
def pnlss_jacobian(A, B, C, D, E, F, expo, lo, hi, u, x, S, y, J):
    """The polynomial state space's sensitivity walk in one pass, sample by sample,
    every column on one thread: the slow twin of ``blockid._kernels.state_space``'s
    two-pass, column-parallel walk (``pnlss_walk``).

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


def fourth_order_arx_halves(n=2000, seed=3):
    """An ARX plant with four poles (0.9, 0.8, 0.5 +- 0.5j) and white equation noise, so
    that an ARX model of orders (4, 2, 1) is the right one and one of fewer poles is
    under-modelled: its record split into estimation and validation halves."""
    rng = np.random.default_rng(seed)
    u, e = rng.standard_normal(n), 0.05 * rng.standard_normal(n)
    a = np.poly([0.9, 0.8, 0.5 + 0.5j, 0.5 - 0.5j]).real  # 1 + a1 q^-1 + ... + a4 q^-4
    y = np.zeros(n)
    for t in range(4, n):
        y[t] = -a[1:] @ y[t - 4 : t][::-1] + u[t - 1] + 0.5 * u[t - 2] + e[t]
    data = Dataset.from_arrays(u, y, ["u"], ["y"])
    return data.select(0, n // 2), data.select(n // 2, n)


#: A small search for tests: 3 folds, orders up to 3, delays up to 2, 3 block families.
SMALL = Effort("small", 3, 2, 3, 2, 1, 3, 15, 10_000, 2, 40, 1)


def dead_zone_record(n=1200, seed=0, noise=0.01):
    """A Hammerstein plant with a dead zone, driven by a staircase (identify's tests)."""
    plant = Hammerstein("u", "y", input_block=DeadZone(-0.3, 0.3, 1.0, 1.0),
                        na=2, nb=2, nk=1, a=[-1.2, 0.5], b=[1.0, 0.4])  # fmt: skip
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(-1, 1, n // 4), 4)
    y = plant.simulate(u)[:, 0] + noise * rng.standard_normal(u.size)
    return Dataset.from_arrays(u, y, ["u"], ["y"])


def scored(structure, relative, **options):
    """A Score with the given folds' relative errors (no fit behind it)."""
    from blockid.workflows.identify import FoldScore, Score
    from blockid.workflows.search_space import Candidate

    folds = [FoldScore(rmse=r, relative=r, n_parameters=4) for r in relative]
    return Score(Candidate(structure, {"na": 2, "nb": 2, "nk": 1, **options}), "structures",
                 folds, rmse=float(np.exp(np.mean(np.log(relative)))), n_parameters=4)  # fmt: skip


#: Linear state spaces whose matrices are known (the state-space fitting tests).
STATE_SPACES = {
    "siso, 2 states": StateSpace(
        ["u"], ["y"], A=[[1.2, -0.35], [1.0, 0.0]], B=[[1.0], [0.0]], C=[[1.0, 0.4]], D=[[0.0]]
    ),  # fmt: skip
    "2 in, 2 out, 3 states": StateSpace(
        ["u1", "u2"],
        ["y1", "y2"],
        A=[[0.8, 0.2, 0.0], [-0.2, 0.8, 0.1], [0.0, 0.0, 0.5]],
        B=[[1.0, 0.0], [0.0, 1.0], [0.5, 0.5]],
        C=[[1.0, 0.0, 0.3], [0.0, 1.0, 0.0]],
        D=[[0.0, 0.0], [0.0, 0.0]],
    ),  # fmt: skip
    "1 in, 2 out, 4 states, feedthrough": StateSpace(
        ["u"],
        ["y1", "y2"],
        A=np.diag([0.9, -0.5, 0.3, 0.6]) + np.diag([0.2, 0.1, 0.0], 1),
        B=[[1.0], [1.0], [0.5], [-1.0]],
        C=[[1.0, 0.0, 1.0, 0.0], [0.0, 1.0, 0.0, 1.0]],
        D=[[0.5], [0.0]],
    ),  # fmt: skip
}


def state_space_record(plant, n, seed=0, snr_db=None, mean=0.3):
    """``n`` samples of ``plant`` driven by white noise around ``mean`` (and output noise
    at ``snr_db``)."""
    rng = np.random.default_rng(seed)
    u = mean + rng.standard_normal((n, len(plant.inputs)))
    y = plant.simulate(u)
    if snr_db is not None:
        y = y + rng.standard_normal(y.shape) * y.std(axis=0) * 10 ** (-snr_db / 20)
    return Dataset.from_arrays(u, y, list(plant.inputs), list(plant.outputs))


def free_run_error(model, plant, n=3000, seed=99):
    """RMSE of ``model``'s free run against the noise-free plant on a fresh record."""
    u = state_space_record(plant, n, seed=seed).experiments[0].u
    return float(np.sqrt(np.mean((model.simulate(u) - plant.simulate(u)) ** 2)))


#: The orders of the fleet's records; the record with a non-numeric cell; how many.
FLEET_ORDERS = {"na": 2, "nb": 2, "nk": 1}
CORRUPT = 7
N_RECORDS = 20


def fleet_records(folder):
    """Twenty small ARX records in ``folder`` (loop00.csv ...), record :data:`CORRUPT` with
    a non-numeric cell; their paths, sorted."""
    import pandas as pd

    from blockid.models import ARX

    plant = ARX(["u"], ["y"], **FLEET_ORDERS, a={"y": {"y": [-1.2, 0.35]}},
                b={"y": {"u": [1.0, 0.4]}})  # fmt: skip
    for i in range(N_RECORDS):
        rng = np.random.default_rng(i)
        u = rng.uniform(-1, 1, 400)
        y = plant.simulate(u)[:, 0] + 0.01 * rng.standard_normal(400)
        frame = pd.DataFrame({"u": u, "y": y}).astype(object)
        if i == CORRUPT:
            frame.loc[100, "u"] = "abc"
        frame.to_csv(folder / f"loop{i:02d}.csv", index=False)
    return sorted(folder.glob("*.csv"))


def key_term_hw_plant() -> HammersteinWiener:
    """Paper B's kind of Hammerstein-Wiener plant (na = nb = 3, nk = 8): the stream's claim."""
    n1 = TwoSegmentPolynomial.from_segments(
        positive=[0, 0.3, 0.1, -0.05], negative=[0, 0.15, -0.05, 0.03]
    )
    return HammersteinWiener(
        "u",
        "y",
        input_block=n1,
        output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
        na=3,
        nb=3,
        nk=8,
        a=np.real(np.poly([0.7, 0.5, -0.3]))[1:],
        b=[1.0, 0.5, 0.2],
    )


def key_term_hw_record(n: int, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, (n, 1))
    return u, key_term_hw_plant().simulate(u) + 0.001 * rng.standard_normal((n, 1))


def csv_text(u: np.ndarray, y: np.ndarray) -> str:
    """A record of one input and one output as the CSV text a stream reads (u, y)."""
    rows = [f"{a!r},{b!r}" for a, b in zip(u[:, 0].tolist(), y[:, 0].tolist(), strict=True)]
    return "u,y\n" + "\n".join(rows) + "\n"


def arx_csv_text(n: int = 300) -> str:
    """``n`` samples of a first-order ARX plant as stream text."""
    plant = ARX(["u"], ["y"], na=1, nb=1, nk=1, a={"y": {"y": [-0.5]}}, b={"y": {"u": [2.0]}})
    u = np.random.default_rng(5).uniform(-1, 1, (n, 1))
    return csv_text(u, plant.simulate(u))


def flat_parameters(parameters) -> np.ndarray:
    """A model document's parameters (nested dicts of lists) as one flat array."""
    if isinstance(parameters, dict):
        return np.concatenate([flat_parameters(v) for v in parameters.values()])
    return np.atleast_1d(np.asarray(parameters, dtype=float))


#: An ARX plant of orders (2, 2, 1): the stream's live plant (issue 37).
PLANT_221 = ARX(
    ["u"], ["y"], na=2, nb=2, nk=1, a={"y": {"y": [-1.5, 0.7]}}, b={"y": {"u": [1.0, 0.5]}}
)


GLITCH_ROW = 70  # the row of the issue ("diverged at sample 71")


def record_221(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((n, 1))
    return u, PLANT_221.simulate(u) + 0.01 * rng.standard_normal((n, 1))


# ------------------------------------------------------------------ electrohydraulic twin
#: The electrohydraulic plant's documented parameters, the twin's default.
EH_PARAMETERS = ElectrohydraulicParameters()


def ref_geometry(h, par=EH_PARAMETERS):
    """Arm angle by the law of cosines; derivatives by the chain rule."""
    a, b = par.pin_base_distance, par.pin_rod_distance
    length = par.retracted_length + h
    phi = math.acos((a * a + b * b - length * length) / (2 * a * b))
    dphi = length / (a * b * math.sin(phi))
    d2phi = 1 / (a * b * math.sin(phi)) - length * math.cos(phi) * dphi / (
        a * b * math.sin(phi) ** 2
    )
    return phi + par.angle_offset, dphi, d2phi


def ref_area(xv, par=EH_PARAMETERS):
    """Metering area: overlap, then a V-notch (quadratic), then the full slot (linear)."""
    opening = abs(xv) - par.spool_overlap
    if opening <= 0:
        return 0.0
    if opening <= par.notch_length:
        # V-notch: width W * opening / x_n grows linearly, area is its integral.
        return 0.5 * par.area_gradient * opening**2 / par.notch_length
    return 0.5 * par.area_gradient * par.notch_length + par.area_gradient * (
        opening - par.notch_length
    )


def ref_flow(xv, p1, p2, par=EH_PARAMETERS):
    """Four-way valve flows into chamber 1 and out of chamber 2."""
    k = par.discharge_coefficient * ref_area(xv, par) * math.sqrt(2 / par.oil_density)

    def root(dp):
        return dp / (dp**2 + par.transition_pressure**2) ** 0.25

    ps, pr = par.supply_pressure, par.return_pressure
    if xv >= 0:
        return k * root(ps - p1), k * root(p2 - pr)
    return -k * root(p1 - pr), -k * root(ps - p2)


def ref_pilot_setpoint(current, par=EH_PARAMETERS):
    """Pilot pressure difference the two pilot valves settle to."""
    if abs(current) <= par.deadband_current:
        return 0.0
    level = min(par.pilot_gain * (abs(current) - par.deadband_current), par.pilot_pressure_max)
    return math.copysign(level, current)


def ref_spool_rate(xv, pp, par=EH_PARAMETERS):
    """Spool: pilot force against the preloaded spring, viscous pilot-flow damping."""
    drive = par.spool_end_area * pp
    if xv == 0:
        if abs(drive) <= par.spool_preload:
            return 0.0  # held by the spring retainers
        spring = math.copysign(par.spool_preload, drive)
    else:
        spring = par.spool_stiffness * xv + math.copysign(par.spool_preload, xv)
    rate = (drive - spring) / par.spool_damping
    if abs(xv) >= par.spool_max and rate * xv > 0:
        return 0.0  # end cap
    return rate


def ref_rhs(x, current, par=EH_PARAMETERS):
    h, v, p1, p2, xv, pp = x
    theta, dth, d2th = ref_geometry(h, par)
    mass = par.piston_mass + par.arm_inertia * dth**2
    dmass = 2 * par.arm_inertia * dth * d2th
    gravity = par.arm_mass * par.gravity * par.arm_com_distance * math.cos(theta) * dth
    spring = par.spring_stiffness * (h - par.spring_free_position)
    stribeck = par.coulomb_friction + (par.static_friction - par.coulomb_friction) * math.exp(
        -((v / par.stribeck_velocity) ** 2)
    )
    friction = stribeck * math.tanh(v / par.friction_smoothing_velocity)
    force = (
        par.area_head * p1
        - par.area_rod * p2
        - friction
        - par.viscous_friction * v
        - gravity
        - spring
        - par.external_load
    )
    q1, q2 = ref_flow(xv, p1, p2, par)
    v1 = par.dead_volume_head + par.area_head * h
    v2 = par.dead_volume_rod + par.area_rod * (par.stroke - h)
    beta1 = par.bulk_modulus * (1 - math.exp(-p1 / par.air_pressure))
    beta2 = par.bulk_modulus * (1 - math.exp(-p2 / par.air_pressure))
    leak = par.internal_leakage * (p1 - p2)
    dp1 = beta1 / v1 * (q1 - par.area_head * v - leak - par.external_leakage * p1)
    dp2 = beta2 / v2 * (-q2 + par.area_rod * v + leak - par.external_leakage * p2)
    dxv = ref_spool_rate(xv, pp, par)
    dpp = (ref_pilot_setpoint(current, par) - pp) / par.pilot_time_constant
    return np.array([v, (force - 0.5 * dmass * v * v) / mass, dp1, dp2, dxv, dpp])


def ref_simulate(current, x0, par=EH_PARAMETERS, ts=0.05):
    """solve_ivp (DOP853) per sample interval, the delayed current held constant.

    An explicit method: an implicit one's Newton iterates step across ``xv = 0`` onto
    the wrong branch of the spring's preload when the spool leaves neutral.

    The spool's return to neutral is an event: where it reaches zero the integration
    restarts from ``xv = 0``, where ``ref_spool_rate`` holds it while the pilot force
    is below the preload (or lets it pass through when the pilot drives it on).
    """
    delay = int(round(par.input_delay / ts))
    scale = np.array([1e-6, 1e-6, 10.0, 10.0, 1e-9, 10.0])
    states = [np.asarray(x0, float)]
    x = np.asarray(x0, float)

    def crossing(t, y):
        return y[4]

    crossing.terminal = True
    for k in range(len(current) - 1):
        u = current[k - delay] if k >= delay else 0.0
        t, end = k * ts, (k + 1) * ts
        while t < end:
            sol = solve_ivp(
                lambda t, y, u=u: ref_rhs(y, u, par),
                (t, end),
                x,
                method="DOP853",
                rtol=1e-9,
                atol=scale,
                first_step=1e-4,
                max_step=2e-3,
                events=crossing if x[4] != 0.0 else None,
            )
            if sol.status == 1:  # the spool reached neutral
                t, x = sol.t_events[0][0], sol.y_events[0][0].copy()
                x[4] = 0.0
            else:
                t, x = end, sol.y[:, -1]
        states.append(x)
    return np.array(states)


def _load(path):
    spec = importlib.util.spec_from_file_location(f"exported_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write(path, text):
    """Write ``text`` to ``path`` (UTF-8); return the path."""
    path.write_text(text, encoding="utf-8")
    return path


def _with_errors(result, errors):
    """A compare result whose first model's fit carries ``errors`` as standard errors."""
    score = result.models[0]
    fit = dataclasses.replace(score.fit, settings={**score.fit.settings, "standard_errors": errors})
    return dataclasses.replace(result, models=[dataclasses.replace(score, fit=fit)])
