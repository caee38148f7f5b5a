"""Hammerstein models of several inputs and outputs on a matrix-ARX core, by linear
regression: least squares at once, or recursive (RLS, online).

The model is a static polynomial on every input channel before one multivariable ARX
core,

.. math::

    y(t) + \\sum_{k=1}^{n_a} A_k\\, y(t-k) = \\sum_{c=1}^{n_u} \\sum_{l=0}^{n_b-1}
    b_{c,l}\\, f_c\\big(u_c(t - n_k - l)\\big), \\qquad
    f_c(u) = \\sum_{p=1}^{r} \\gamma_{c,p}\\, u^p,

(``A_k`` full ``ny x ny`` matrices, ``b_{c,l}`` columns of ``ny``). Its right-hand side is
linear in the products ``b_{c,l} γ_{c,p}``: with the powers ``u_c^p`` as ``nu r`` inputs
of an ARX model, every coefficient enters a linear regression (Chang & Luus 1971; Bai
1998, "An optimal two-stage identification algorithm for Hammerstein-Wiener nonlinear
systems", Automatica 34(3)). That ARX is fitted by :func:`~blockid.fitting.arx.fit_arx`
(least squares, RLS, the forgetting of paper B, one recursion per output), and its
coefficients of each channel, a ``(ny nb) x r`` matrix ``M_c`` whose rows are
``b_{c,l}`` and columns the powers, are split into the block and the core by the
**rank-1 approximation** of ``M_c`` (its first singular pair): ``γ_c`` the right
singular vector, scaled so that the linear coefficient ``γ_{c,1}`` is 1 (the family's
normalisation, :class:`~blockid.models.block_state_space.BlockStateSpace`; where it is
below 10 % of the vector's norm, unit norm instead), and ``b_c`` the rest. The second
singular value over the first is recorded per channel (``settings["rank_ratio"]``): a
large one says the data do not support one static block per channel.

The result is a :class:`~blockid.models.block_state_space.BlockStateSpace` whose core
realises the ARX (a state of the last ``na`` outputs and the last ``nk + nb - 1``
block outputs), so it simulates, saves, exports and reports as every block model of
several channels, and its initial state is estimated from measured outputs as theirs.
The recursive method learns online (:mod:`blockid.fitting.online`): ``partial_fit``,
``update``, ``blockid stream --structure block-state-space --method rls``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from blockid.blocks.base import StaticBlock, block_template
from blockid.data.dataset import Dataset, Experiment
from blockid.defaults import FORGETTING
from blockid.errors import EstimationError, ParameterError
from blockid.fitting.options import checked
from blockid.fitting.result import FitResult, simulation_result
from blockid.fitting.state_space import _check, signal_statistics
from blockid.models.arx import ARX
from blockid.models.block_state_space import BlockStateSpace

__all__ = [
    "CONSTANT",
    "Basis",
    "arx_core_model",
    "fit_block_arx",
    "input_basis",
    "regression_orders",
    "scalar_orders",
]

#: Below this share of the block's coefficient norm the first basis function's
#: coefficient is not used to normalise it (the block would be scaled by a near-zero
#: number).
FIRST_SHARE = 0.1
#: The name of the regression's constant input (an intercept per output).
CONSTANT = "(constant)"
#: Where a block's basis is probed for constant and dependent functions.
_PROBE = np.linspace(-3.0, 3.0, 61)


class Basis:
    """The basis functions of an input block linear in its parameters: its
    ``regressors`` less those that are constant (the intercept holds them)."""

    def __init__(self, template: StaticBlock) -> None:
        self.template = template
        probe = np.asarray(template.regressors(_PROBE), dtype=float)
        self.varying = np.flatnonzero(np.ptp(probe, axis=0) > 0)
        self.size = int(self.varying.size)
        with_constant = np.column_stack([np.ones(_PROBE.size), probe[:, self.varying]])
        if self.size == 0 or np.linalg.matrix_rank(with_constant) < self.size + 1:
            raise ParameterError(
                f"the regression methods need an input block whose basis functions and a "
                f"constant are independent; {template.kind}'s are not (its functions sum "
                "to a constant, or it has none): use --method simulation-error",
                parameter="input_block",
            )
        self.names = [template.vector_names()[j] for j in self.varying]

    def functions(self, u: np.ndarray) -> np.ndarray:
        """``φ(u)`` of one channel's samples, shape (N, size)."""
        return np.asarray(self.template.regressors(u), dtype=float)[:, self.varying]

    def block(self, gamma: np.ndarray) -> StaticBlock:
        """The block whose varying coefficients are ``gamma`` (constant ones zero)."""
        theta = np.zeros(self.template.to_vector().size)
        theta[self.varying] = gamma
        return self.template.with_vector(theta)

    def inputs(self, names: tuple[str, ...]) -> tuple[str, ...]:
        """The ARX inputs of the regression: ``u1[coefficients_1] ..``, then the constant."""
        return (*(f"{n}[{b}]" for n in names for b in self.names), CONSTANT)

    def expanded(self, u: np.ndarray) -> np.ndarray:
        """``u`` (N, nu) -> every channel's basis functions, then a column of ones."""
        u = np.asarray(u, dtype=float)
        parts = [self.functions(u[:, c]) for c in range(u.shape[1])]
        return np.concatenate([*parts, np.ones((u.shape[0], 1))], axis=1)


def input_basis(input_block: Any, output_block: Any = None) -> Basis:
    """The basis of the input blocks an ``input_block`` asks for (default: a cubic);
    refuses what the linear regression cannot hold, naming the option."""
    if output_block is not None:
        raise ParameterError(
            "the regression methods (batch, rls) fit input blocks only (a Hammerstein "
            "model); for output blocks use --method simulation-error",
            parameter="output_block",
        )
    if isinstance(input_block, dict):
        raise ParameterError(
            "the regression methods take one input block family for every channel (one "
            "--input-block KIND); per-channel blocks need --method simulation-error",
            parameter="input_block",
        )
    spec = "polynomial:degree=3" if input_block is None else input_block
    block = block_template(spec) if isinstance(spec, str) else spec
    if not getattr(block, "linear_in_parameters", False) or getattr(block, "role", "") != "static":
        raise ParameterError(
            f"the regression methods need an input block linear in its parameters (a "
            f"polynomial, a two-segment polynomial), not {block.kind}: use --method "
            "simulation-error for other families",
            parameter="input_block",
        )
    return Basis(block)


def regression_orders(
    ny: int, nu: int, n_basis: int, na: int, nb: int, nk: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The ARX order matrices of the regression: ``na`` on every output pair, ``nb`` and
    ``nk`` on every basis function, the constant entering once without delay."""
    n = nu * n_basis + 1
    NB, NK = np.full((ny, n), nb), np.full((ny, n), nk)
    NB[:, -1], NK[:, -1] = 1, 0
    return np.full((ny, ny), na), NB, NK


def arx_core_model(
    arx: ARX,
    inputs: tuple[str, ...],
    basis: Basis,
    *,
    input_range: np.ndarray | None = None,
    sampling_time: float | None = None,
) -> tuple[BlockStateSpace, list[float]]:
    """The block model of an ARX on the basis functions (module docstring) and, per
    channel, the second singular value of its coefficient matrix over the first."""
    ny, nu, n = len(arx.outputs), len(inputs), basis.size
    na = int(arx.na.max(initial=0))
    functions = slice(0, nu * n)  # the constant input comes after them
    nb = int(arx.nb[:, functions].max(initial=0))
    nk = int(arx.nk[:, functions].min()) if nu else 0
    blocks, ratios = [], []
    b = np.zeros((nu, ny, nb))  # b[c][i, l]: coefficient of w_c(t - nk - l) in output i
    for c in range(nu):
        M = np.zeros((ny * nb, n))
        for i in range(ny):
            for p in range(n):
                coeffs = arx.b[arx.outputs[i]][arx.inputs[c * n + p]]
                M[i * nb : i * nb + coeffs.size, p] = coeffs
        U, s, Vt = np.linalg.svd(M, full_matrices=False)
        ratios.append(float(s[1] / s[0]) if s.size > 1 and s[0] > 0 else 0.0)
        gamma, column = Vt[0] * s[0], U[:, 0]
        norm = float(np.linalg.norm(gamma))
        first = gamma[0] if norm > 0 and abs(gamma[0]) >= FIRST_SHARE * norm else norm or 1.0
        blocks.append(basis.block(gamma / first))
        b[c] = (column * first).reshape(ny, nb)
    a = np.zeros((na, ny, ny))  # a[k-1][i, j]: coefficient of y_j(t-k) in output i
    for i, yi in enumerate(arx.outputs):
        for j, yj in enumerate(arx.outputs):
            a[: arx.a[yi][yj].size, i, j] = arx.a[yi][yj]
    A, B, C, D = _realisation(a, b, nk)
    # the intercept d: y(t) = C x + D w + d, and y(t) enters the state
    d = np.array([arx.b[yi][CONSTANT][0] for yi in arx.outputs])
    bias = np.zeros(A.shape[0])
    if na:
        bias[:ny] = d
    model = BlockStateSpace(
        inputs, arx.outputs, A, B, C, D,
        input_blocks=blocks, state_bias=bias, output_bias=d,
        input_range=input_range, sampling_time=sampling_time,
    )  # fmt: skip
    return model, ratios


def _realisation(
    a: np.ndarray, b: np.ndarray, nk: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A state-space realisation of ``y(t) = -Σ a[k-1] y(t-k) + Σ b[c][:, l] w_c(t-nk-l)``:
    the state holds ``y(t-1) .. y(t-na)`` and ``w(t-1) .. w(t-m)``, ``m = nk + nb - 1``
    (the largest lag of ``w``), so ``x(t+1)`` shifts them and puts in ``y(t)``, ``w(t)``.
    ``a`` (na, ny, ny); ``b`` (nu, ny, nb)."""
    na, ny = a.shape[0], b.shape[1]
    nu, nb = b.shape[0], b.shape[2]
    m = nk + nb - 1
    nx = ny * na + nu * m
    C = np.zeros((ny, nx))
    D = np.zeros((ny, nu))
    for k in range(na):
        C[:, k * ny : (k + 1) * ny] = -a[k]
    for lag_index in range(nb):
        lag = nk + lag_index  # w(t - lag)
        if lag == 0:
            D += b[:, :, lag_index].T
        else:
            at = ny * na + (lag - 1) * nu
            C[:, at : at + nu] += b[:, :, lag_index].T
    A = np.zeros((nx, nx))
    B = np.zeros((nx, nu))
    if na:
        A[:ny] = C
        B[:ny] = D
        A[ny : ny * na, : ny * (na - 1)] = np.eye(ny * (na - 1))
    if m:
        at = ny * na
        B[at : at + nu] = np.eye(nu)
        A[at + nu : at + nu * m, at : at + nu * (m - 1)] = np.eye(nu * (m - 1))
    return A, B, C, D


def scalar_orders(na: Any, nb: Any, nk: Any) -> tuple[int, int, int]:
    """The orders as one whole number each, checked (``nb >= 1``: the inputs enter)."""
    for name, value in (("na", na), ("nb", nb), ("nk", nk)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer):
            raise ParameterError(
                f"{name} of a block model on an ARX core is one whole number for every "
                f"channel pair, got {value!r}",
                parameter=name,
            )
    na, nb, nk = (int(checked(k, v)) for k, v in (("na", na), ("nb", nb), ("nk", nk)))
    if nb < 1:
        raise ParameterError("nb must be at least 1: the inputs must enter", parameter="nb")
    return na, nb, nk


def fit_block_arx(
    data: Dataset,
    *,
    method: str = "batch",
    input_block: Any = None,
    output_block: Any = None,
    na: int = 2,
    nb: int = 2,
    nk: int = 1,
    forgetting: Any = FORGETTING,
    initial_covariance: float | None = None,
    passes: int = 1,
) -> FitResult:
    """Hammerstein model of several inputs and outputs on a matrix-ARX core, by the
    linear regression on the input blocks' basis functions and the rank-1 split (module
    docstring).

    Parameters
    ----------
    data : Dataset
    method : {"batch", "rls"}
        Least squares at once, or the recursion (:func:`~blockid.fitting.arx.fit_arx`).
    input_block : str or StaticBlock, optional
        The family of every input block, linear in its parameters (default
        ``polynomial:degree=3``).
    na, nb, nk : int
        Orders of every output-output and input-output pair.
    forgetting, initial_covariance, passes
        Of the recursive method (:func:`~blockid.fitting.arx.fit_arx`).
    """
    from blockid.fitting.arx import fit_arx

    basis = input_basis(input_block, output_block)
    na, nb, nk = scalar_orders(na, nb, nk)
    signal_statistics(data)  # every signal must move, inputs not together: else named
    names = basis.inputs(tuple(data.inputs))
    expanded = Dataset(
        list(names), list(data.outputs), data.sampling_time,
        [Experiment(e.name, basis.expanded(e.u), e.y) for e in data.experiments], data.source,
    )  # fmt: skip
    orders = regression_orders(data.n_outputs, data.n_inputs, basis.size, na, nb, nk)
    inner = fit_arx(
        expanded, *orders, method=method, forgetting=forgetting,
        initial_covariance=initial_covariance, passes=passes, max_mse_ratio=None,
    )  # fmt: skip
    arx = inner.model
    u_all = np.vstack([e.u for e in data.experiments])
    model, ratios = arx_core_model(
        arx, tuple(data.inputs), basis,
        input_range=np.column_stack([u_all.min(axis=0), u_all.max(axis=0)]),
        sampling_time=data.sampling_time,
    )  # fmt: skip
    if not model.is_stable():
        raise EstimationError(
            f"the {method} regression's ARX core is unstable (largest pole magnitude "
            f"{float(np.max(np.abs(arx.poles()))):.4g}); no model is returned: try other "
            "orders (na, nb, nk) or --method simulation-error"
        )
    metrics = _check(model, data, f"block-arx {method}")
    settings = {
        "method": method,
        "input_block": basis.template.kind,
        "na": na,
        "nb": nb,
        "nk": nk,
        "rank_ratio": dict(zip(data.inputs, ratios, strict=True)),
        "regression": inner.settings,
    }
    return simulation_result(
        model, data, f"block-arx-{method}", settings, metrics, dict(inner.history)
    )
