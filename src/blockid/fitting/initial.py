"""Initial estimates of block-oriented models, the starting points of the refinement.

None of these is the final answer: :func:`blockid.fitting.simulation_error.refine`
minimises the free-run simulation error from here. They only have to be cheap, stable
and close enough for a Gauss-Newton method to converge.

Hammerstein (static input block linear in its parameters, e.g. the two-segment
polynomial B1): the over-parameterised linear regression

.. math::

    y(k) = -\\sum_{j=1}^{n_a} a_j\\, y(k-j)
           + \\sum_{i=0}^{n_b-1} \\sum_{l} c_{il}\\, g_l(u(k - n_k - i)),
    \\qquad c_{il} = b_i \\theta_l

with ``g`` the block's basis (``regressors``), solved by least squares (QR), then the
rank-one factorisation ``C ≈ b θᵀ`` by SVD, normalised ``b_0 = 1``. A basis that spans
the constant function (``1`` of B1, the hat functions of a piecewise-linear block) would
make the constant column repeat at every lag; the basis is rotated so that the constant
appears once, and its coefficient ``B(1) θ_0`` gives ``θ_0`` after the factorisation.

Hammerstein-Wiener and Wiener: the linear part is first fitted with the output block
taken as the identity (``q = [1, 0, ..]``): a Hammerstein estimate as above, or a plain
ARX fit for Wiener. Then a short alternating scheme improves the output block: fit
``q`` by least squares from the simulated ``x̂`` to ``y``, move the gain ``q_1`` into the
linear part (``q_1 = 1`` again), invert the new output block on ``y`` where it is
monotone, ``x̃ = N_2^{-1}(y)``, and refit the linear part on ``x̃`` (three rounds).

Candidates are scored by their free-run simulation error on the data and the best is
returned. The plain ARX fit, written as a block model (input block set to the line
``b_0 u`` where the block can represent it, identity output block, and with ``q``
fitted as above), is always among the candidates, so the start is never worse than a
linear model: on the simulated electrohydraulic plant of paper B the over-parameterised
regression alone gave a start ten times worse than ARX.

Static blocks that are not linear in their parameters, and the backlash (A3): a small
grid over the block's shape, every grid point completed by linear least squares and
scored by its free-run simulation error; the best one wins.

* backlash: equal slopes and ``c_L = c_R = c`` **(choice)**, ``c`` on a grid
  of fractions of the input's range, refined once on a finer grid around the best;
  for each ``c`` the unit-slope backlash gives ``w`` and an ARX fit from ``w`` gives the
  linear block, whose ``b_0`` becomes the slope (so ``b_0 = 1`` afterwards). The
  backlash simulator is compiled, so the grid costs a few milliseconds;
* dead zone: edges ``[-f_1 U, f_2 U]`` (``U = max |u|``) on a 7 x 7 grid; for fixed edges
  the dead zone is linear in its two slopes, so both slopes and the linear block come
  from the rank-one regression above;
* saturation: knees at ``u = -f_1 U`` and ``f_2 U`` on a 6 x 6 grid, slope from ``b_0`` of
  the ARX fit as for the backlash.

The grids contain ``u = 0`` in the dead band and between the knees; the refinement
moves the edges from there.

All estimates use the signals as measured (no operating-point offsets): the constant
terms of the input block carry the operating point. A Wiener model has no constant term
anywhere (B3 has none), so it cannot represent an output that does not vanish with
the input; remove such an operating point from the data first. A linear block that comes out
unstable has its unstable poles reflected into the unit circle.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from blockid.blocks import (
    Backlash,
    DeadZone,
    Polynomial,
    Saturation,
    TwoSegmentPolynomial,
)
from blockid.blocks.base import Block, StaticBlock
from blockid.data.dataset import Dataset
from blockid.errors import BlockidError, EstimationError, OrderError, ParameterError
from blockid.estimators import BatchLeastSquares
from blockid.fitting.checks import STABILITY_MARGIN, simulation_mse
from blockid.models.block import (
    BLOCK_STRUCTURES,
    BacklashModel,
    BlockModel,
    Hammerstein,
    HammersteinWiener,
)

__all__ = ["initial_estimate", "resolve_structure", "scaled_block"]

#: Unit-slope shapes tried by the grid search, as fractions of the input scale.
_BACKLASH_GRID = (0.0, 0.0025, 0.005, 0.01, 0.02, 0.035, 0.05, 0.075, 0.1, 0.15, 0.2, 0.3)
_DEAD_ZONE_GRID = (0.0, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6)
_SATURATION_GRID = (0.2, 0.35, 0.5, 0.65, 0.8, 1.0)

#: Rounds of the alternating scheme for models with an output block.
_ROUNDS = 3


def resolve_structure(structure: str | type[BlockModel]) -> type[BlockModel]:
    """The model class of a structure name (``"hammerstein-wiener"``) or class."""
    if isinstance(structure, type) and issubclass(structure, BlockModel):
        if structure.structure not in BLOCK_STRUCTURES:
            raise ParameterError(f"{structure.__name__} is not a block-oriented structure")
        return structure
    if structure not in BLOCK_STRUCTURES:
        known = ", ".join(BLOCK_STRUCTURES)
        raise ParameterError(
            f"structure={structure!r} is not a block-oriented structure; choose one of {known}"
        )
    return BLOCK_STRUCTURES[structure]


def scaled_block(block: Block, gain: float) -> Block:
    """The block followed by a positive ``gain``: ``gain * N(u)`` as a block of its kind.

    Used to move a gain from the linear block into the input block (normalisation
    ``b_0 = 1``).
    """
    if block.linear_in_parameters:
        return block.with_vector(gain * block.to_vector())
    if gain <= 0:
        raise EstimationError(
            f"cannot absorb the gain {gain:.4g} into a {block.kind} block, whose slopes must "
            "be positive: the plant's gain from u has the opposite sign. Negate the input "
            "(or the output) and fit again"
        )
    if isinstance(block, Backlash):
        return Backlash(gain * block.m_left, block.c_left, gain * block.m_right, block.c_right)
    if isinstance(block, DeadZone):
        return DeadZone(block.lower, block.upper, gain * block.slope_left, gain * block.slope_right)
    if isinstance(block, Saturation):
        return Saturation(gain * block.lower, gain * block.upper, gain * block.slope)
    raise ParameterError(
        f"no initial estimate for a {block.kind} input block; pass a starting model "
        "(initial=...) to the simulation-error fit"
    )


# ----------------------------------------------------------------------------- helpers
def _cascade_class(block: Block) -> type[BlockModel]:
    """The structure without output block that has ``block`` as input block."""
    return BacklashModel if isinstance(block, Backlash) else Hammerstein


def _build(
    like: BlockModel,
    input_block: Block | None,
    output_block: Polynomial | None = None,
    a: np.ndarray | None = None,
    b: np.ndarray | None = None,
    cls: type[BlockModel] | None = None,
) -> BlockModel:
    """A model with the names, orders and sampling time of ``like`` (class ``cls``)."""
    cls = cls or type(like)
    kwargs: dict[str, Any] = dict(
        na=like.na, nb=like.nb, nk=like.nk, a=a, b=b, sampling_time=like.sampling_time
    )
    if cls.requires_input_block:
        kwargs["input_block"] = input_block
    if cls.requires_output_block:
        kwargs["output_block"] = output_block
    return cls(like.inputs[0], like.outputs[0], **kwargs)


def _signals(data: Dataset) -> tuple[list[np.ndarray], list[np.ndarray]]:
    return [e.u[:, 0] for e in data.experiments], [e.y[:, 0] for e in data.experiments]


def _lagged(sig: np.ndarray, lag: int, n0: int) -> np.ndarray:
    """``sig(t - lag)`` for ``t = n0 .. N-1``."""
    return sig[n0 - lag : sig.shape[0] - lag]


def _least_squares(Phi: np.ndarray, target: np.ndarray, what: str) -> np.ndarray:
    """QR least squares on RMS-scaled columns (powers of ``u`` differ wildly in scale)."""
    scale = np.sqrt(np.mean(Phi**2, axis=0))
    scale[scale == 0] = 1.0
    try:
        theta = BatchLeastSquares().fit(Phi / scale, target).coef_
    except EstimationError as exc:
        raise EstimationError(f"initial estimate ({what}): {exc}") from None
    return theta / scale


def _stabilise(a: np.ndarray) -> np.ndarray:
    """Move poles on or outside the unit circle inside: ``p -> 0.99 / conj(p)``, and at
    most radius 0.99 (a start for the refinement, which needs poles inside radius
    ``1 - STABILITY_MARGIN``)."""
    if a.size == 0:
        return a
    poles = np.roots(np.concatenate(([1.0], a)))
    mag = np.abs(poles)
    if np.all(mag < 1.0 - STABILITY_MARGIN):
        return a
    fixed = np.where(mag < 1.0, poles, 0.99 * poles / np.maximum(mag, 1e-300) ** 2)
    fixed = np.where(np.abs(fixed) >= 0.99, 0.99 * fixed / np.abs(fixed), fixed)
    return np.real(np.poly(fixed))[1:]


def _max_lag(na: int, nb: int, nk: int) -> int:
    return max(na, nk + nb - 1, 1)


def _constant_rotation(G: np.ndarray) -> tuple[np.ndarray, bool]:
    """Basis change ``T`` with ``(G T)[:, 0] == 1`` when the constant is in span(G).

    Returns ``(T, True)``, ``T = [v, Q]`` with ``G v = 1`` and ``Q`` an orthonormal
    complement of ``v``; or ``(I, False)`` when the basis does not span constants.
    """
    n = G.shape[1]
    ones = np.ones(G.shape[0])
    v, *_ = np.linalg.lstsq(G, ones, rcond=None)
    if np.linalg.norm(G @ v - ones) > 1e-8 * np.sqrt(G.shape[0]):
        return np.eye(n), False
    Q, _ = np.linalg.qr(v[:, None], mode="complete")
    return np.column_stack((v, Q[:, 1:])), True


def _arx_fit(
    w: Sequence[np.ndarray], z: Sequence[np.ndarray], na: int, nb: int, nk: int
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ARX from ``w`` to ``z`` (``b_0`` free); returns stable ``a`` and ``b``."""
    n0 = _max_lag(na, nb, nk)
    Phi = np.vstack(
        [
            np.column_stack(
                [-_lagged(zi, j, n0) for j in range(1, na + 1)]
                + [_lagged(wi, nk + i, n0) for i in range(nb)]
            )
            for wi, zi in zip(w, z, strict=True)
        ]
    )
    target = np.concatenate([zi[n0:] for zi in z])
    theta = _least_squares(Phi, target, "linear block")
    return _stabilise(theta[:na]), theta[na:]


def _rank_one_fit(
    u: Sequence[np.ndarray],
    z: Sequence[np.ndarray],
    basis: Callable[[np.ndarray], np.ndarray],
    na: int,
    nb: int,
    nk: int,
    what: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Over-parameterised regression and rank-one factorisation (module docstring).

    ``basis(u)`` gives the regressors ``g_l(u)``, shape (N, n); returns the block's
    coefficient vector, a stable ``a`` and ``b`` with ``b_0 = 1``.
    """
    n0 = _max_lag(na, nb, nk)
    G = [np.asarray(basis(ui), dtype=float) for ui in u]
    T, has_constant = _constant_rotation(np.vstack(G))
    Gt = [g @ T for g in G]
    k0 = 1 if has_constant else 0  # columns of Gt that vary
    rows = []
    for gi, zi in zip(Gt, z, strict=True):
        cols = [-_lagged(zi, j, n0) for j in range(1, na + 1)]
        if has_constant:
            cols.append(np.ones(zi.shape[0] - n0))
        for i in range(nb):
            cols.extend(_lagged(gi[:, l], nk + i, n0) for l in range(k0, gi.shape[1]))
        rows.append(np.column_stack(cols))
    target = np.concatenate([zi[n0:] for zi in z])
    theta = _least_squares(np.vstack(rows), target, what)
    a = _stabilise(theta[:na])
    C = theta[na + k0 :].reshape(nb, -1)  # C[i, l] = b_i theta_l: rank one by (B1)-(B2)
    U, s, Vt = np.linalg.svd(C, full_matrices=False)
    b = U[:, 0] * s[0]
    if abs(b[0]) <= 1e-8 * np.linalg.norm(b):
        raise EstimationError(
            "initial estimate: b_0 came out as zero, so the normalisation b_0 = 1 is "
            "impossible; the input delay nk is probably too small (raise nk)"
        )
    f = Vt[0] * b[0]
    b = b / b[0]
    if has_constant:
        gain = float(np.sum(b))
        phi0 = theta[na] / gain if abs(gain) > 1e-12 else 0.0
        return T[:, 0] * phi0 + T[:, 1:] @ f, a, b
    return T @ f, a, b


def _hammerstein_ls(
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], block: StaticBlock, template: BlockModel
) -> tuple[StaticBlock, np.ndarray, np.ndarray]:
    """Input block linear in its parameters and linear block, by :func:`_rank_one_fit`."""
    if isinstance(block, TwoSegmentPolynomial):
        u_all = np.concatenate(u)
        if not (np.any(u_all < 0) and np.any(u_all >= 0)):
            raise EstimationError(
                "the input never changes sign, so the two polynomials of the two-segment "
                "input block (B1) cannot both be identified; use data that span both signs "
                "of u, or a Polynomial input block"
            )
    vector, a, b = _rank_one_fit(
        u,
        z,
        block.regressors,
        template.na,
        template.nb,
        template.nk,
        f"{block.kind} Hammerstein regression",
    )
    return block.with_vector(vector), a, b


def _profile_fit(
    unit: Block, u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> BlockModel | None:
    """ARX from ``w = unit(u)`` to ``z``, its ``b_0`` moved into the block (None if <= 0)."""
    probe = _build(template, unit, None, None, None, cls=_cascade_class(unit))
    w = [probe.internal(ui) for ui in u]
    a, b = _arx_fit(w, z, template.na, template.nb, template.nk)
    if not b[0] > 1e-12 * max(np.max(np.abs(b)), 1e-300):
        return None
    return _build(probe, scaled_block(unit, b[0]), None, a, b / b[0])


def _dead_zone_fit(
    lower: float,
    upper: float,
    u: Sequence[np.ndarray],
    z: Sequence[np.ndarray],
    template: BlockModel,
) -> BlockModel | None:
    """For fixed edges a dead zone is linear in its two slopes: rank-one fit of those."""

    def basis(v: np.ndarray) -> np.ndarray:
        return np.column_stack((np.minimum(v - lower, 0.0), np.maximum(v - upper, 0.0)))

    try:
        slopes, a, b = _rank_one_fit(
            u, z, basis, template.na, template.nb, template.nk, "dead zone"
        )
    except EstimationError:  # an edge beyond the data: a slope is not excited
        return None
    if np.any(slopes <= 0):
        return None
    return _build(template, DeadZone(lower, upper, *slopes), None, a, b, cls=Hammerstein)


def _grid_search(
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> tuple[Block, np.ndarray, np.ndarray]:
    """Profile grid search over the block's shape, scored by free-run error on ``z``."""
    block = template.input_block
    u_all = np.concatenate(u)
    span, peak = float(np.ptp(u_all)) or 1.0, float(np.max(np.abs(u_all))) or 1.0
    a_lin, b_lin = _arx_fit(u, z, template.na, template.nb, template.nk)
    if np.sum(b_lin) / (1.0 + np.sum(a_lin)) < 0:  # static gain of a linear fit
        raise EstimationError(
            f"initial estimate: the plant's static gain from u is negative, but a "
            f"{block.kind} block has positive slopes and b_0 = 1. Negate the input (or the "
            "output) and fit again"
        )
    if isinstance(block, Backlash):  # c_L = c_R = c, equal slopes (choice, see module)

        def backlash(c: float) -> BlockModel | None:
            return _profile_fit(Backlash(1.0, c, 1.0, c), u, z, template)

        grid = [span * g for g in _BACKLASH_GRID]
        candidates = [backlash(c) for c in grid]
        k = int(np.argmin([_sse(m, u, z) for m in candidates]))
        fine = np.linspace(grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)], 9)
        candidates += [backlash(c) for c in fine]
    elif isinstance(block, DeadZone):  # edges [-f1 peak, f2 peak], both slopes fitted
        candidates = [
            _dead_zone_fit(-peak * f1, peak * f2, u, z, template)
            for f1 in _DEAD_ZONE_GRID
            for f2 in _DEAD_ZONE_GRID
        ]
    elif isinstance(block, Saturation):  # knees at u = -f1 peak and f2 peak, slope fitted
        candidates = [
            _profile_fit(Saturation(-peak * f1, peak * f2), u, z, template)
            for f1 in _SATURATION_GRID
            for f2 in _SATURATION_GRID
        ]
    else:
        raise ParameterError(
            f"no initial estimate for a {block.kind or type(block).__name__} input block; "
            "pass a starting model (initial=...) to the simulation-error fit"
        )
    errors = [_sse(m, u, z) for m in candidates]
    best = candidates[int(np.argmin(errors))]
    if best is None:
        raise EstimationError(
            f"initial estimate: no {block.kind} shape gave positive slopes; the plant's "
            "gain from u has the opposite sign. Negate the input (or the output) and fit "
            "again"
        )
    return best.input_block, best.a, best.b


def _sse(model: BlockModel | None, u: Sequence[np.ndarray], z: Sequence[np.ndarray]) -> float:
    """Free-run sum of squared errors against ``z`` (inf for no model)."""
    if model is None:
        return np.inf
    n0, err = model.max_lag, 0.0
    for ui, zi in zip(u, z, strict=True):
        with np.errstate(all="ignore"):
            err += float(np.sum((zi[n0:] - model.simulate(ui, zi[:n0])[n0:, 0]) ** 2))
    return err if np.isfinite(err) else np.inf


def _input_and_linear(
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> tuple[Block | None, np.ndarray, np.ndarray]:
    """Input block and linear block fitted to the target ``z`` (output block ignored)."""
    block = template.input_block
    if block is None:
        a, b = _arx_fit(u, z, template.na, template.nb, template.nk)
        return None, a, b
    if block.linear_in_parameters:
        return _hammerstein_ls(u, z, block, template)
    return _grid_search(u, z, template)


def _output_polynomial(x: Sequence[np.ndarray], y: Sequence[np.ndarray], r2: int, n0: int):
    """Least-squares ``q`` of ``y = sum_m q_m x^m`` (free ``q_1``)."""
    Phi = np.vstack([np.vander(xi[n0:], r2 + 1, increasing=True)[:, 1:] for xi in x])
    target = np.concatenate([yi[n0:] for yi in y])
    return _least_squares(Phi, target, "output polynomial")


def _score(model: BlockModel, data: Dataset) -> float:
    try:
        with np.errstate(all="ignore"):
            stable = model.is_stable(STABILITY_MARGIN)
            return simulation_mse(model, data) if stable else np.inf
    except BlockidError:
        return np.inf


def _linear_start(
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> tuple[Block | None, np.ndarray, np.ndarray] | None:
    """The plain ARX fit as a block model: the input block set to the line ``b_0 u``.

    Only for input blocks linear in their parameters that can represent a line
    exactly (two-segment and ordinary polynomials, piecewise-linear maps); None
    otherwise (the grids of the other blocks contain their near-linear shapes).
    """
    block = template.input_block
    a, b = _arx_fit(u, z, template.na, template.nb, template.nk)
    if block is None:
        return None, a, b
    if not block.linear_in_parameters or not b[0] != 0:
        return None
    u_all = np.concatenate(u)
    G = np.asarray(block.regressors(u_all), dtype=float)
    v, *_ = np.linalg.lstsq(G, u_all, rcond=None)
    if np.max(np.abs(G @ v - u_all)) > 1e-9 * (np.max(np.abs(u_all)) + 1e-300):
        return None
    return block.with_vector(b[0] * v), a, b / b[0]


def _with_q(
    model: BlockModel, u: Sequence[np.ndarray], y: Sequence[np.ndarray], r2: int
) -> tuple[BlockModel | None, np.ndarray]:
    """Fit ``q`` from the simulated ``x`` of ``model`` (identity output block) to ``y``.

    Returns the model with that output block, ``q_1`` moved into the linear part
    (``x' = q_1 x``: ``q'_m = q_m / q_1^m``, input block or ``b`` times ``q_1``), and
    the simulated ``x'``; None for the model if ``q_1 <= 0``.
    """
    n0 = model.max_lag
    x = [model.simulate(ui)[:, 0] for ui in u]  # y = x with the identity block
    q = _output_polynomial(x, y, r2, n0)
    g = float(q[0])
    if not g > 0:
        return None, np.concatenate(x)
    q = q / g ** np.arange(1, r2 + 1)
    block, b = model.input_block, model.b
    if block is None:
        b = g * b
    else:
        block = scaled_block(block, g)
    return _build(model, block, Polynomial(q, constant=False), model.a, b), g * np.concatenate(x)


def _with_output_block(data: Dataset, template: BlockModel, r2: int) -> list[BlockModel]:
    """Candidates of the alternating scheme for Wiener and H-W (module docstring)."""
    u, y = _signals(data)
    identity = Polynomial([1.0] + [0.0] * (r2 - 1), constant=False)
    candidates: list[BlockModel] = []
    linear = _linear_start(u, y, template)
    if linear is not None and template.input_block is not None:
        candidates.append(_build(template, linear[0], identity, linear[1], linear[2]))
        if r2 > 1:
            candidates.append(_with_q(candidates[-1], u, y, r2)[0])
    z = y
    for _ in range(_ROUNDS):
        block, a, b = _input_and_linear(u, z, template)
        candidates.append(_build(template, block, identity, a, b))
        if r2 == 1:
            break
        model, x = _with_q(candidates[-1], u, y, r2)
        if model is None:
            break
        candidates.append(model)
        lo, hi = float(np.min(x)), float(np.max(x))
        margin = 0.25 * (hi - lo) + 1e-12
        try:
            z = [
                model.output_block.inverse(yi, u_range=(lo - margin, hi + margin), clip=True)
                for yi in y
            ]
        except BlockidError:
            break
    return candidates


# ----------------------------------------------------------------------------- public
def initial_estimate(
    data: Dataset,
    structure: str | type[BlockModel],
    *,
    na: int,
    nb: int,
    nk: int,
    r1: int = 3,
    r2: int = 3,
    input_block: Block | None = None,
) -> BlockModel:
    """A cheap, stable starting model of a block-oriented structure (module docstring).

    Parameters
    ----------
    data : Dataset
        Estimation data with one input and one output. For the two-segment input block
        (B1) the input must take both signs, or its ``p`` parameters are not
        identifiable.
    structure : str or type
        ``"hammerstein"``, ``"wiener"``, ``"hammerstein-wiener"`` or ``"backlash"`` (or
        the model class).
    na, nb, nk : int
        Orders of the linear block (MATLAB convention).
    r1 : int, default 3
        Order of the default two-segment polynomial input block (B1).
    r2 : int, default 3
        Degree of the output polynomial (B3), ``y = x + q_2 x^2 + .. + q_r2 x^r2``.
    input_block : Block, optional
        Template of the input block: its kind and form (order, breakpoints) are used,
        its parameter values are not. Default: ``TwoSegmentPolynomial`` of order ``r1``
        (a ``Backlash`` for the backlash structure).

    Returns
    -------
    BlockModel
        A model of the structure with a stable linear block, ``b_0 = 1`` with an input
        block and ``q_1 = 1`` with an output block.

    Raises
    ------
    EstimationError
        If the data do not determine the parameters (e.g. rank-deficient regression).
    OrderError, ParameterError
        If the orders, the data's signals or the options are invalid.
    """
    cls = resolve_structure(structure)
    template = _template(cls, data, na, nb, nk, r1, r2, input_block)
    n_par = template.free_parameters().size
    data.check_orders(template.max_lag, n_par, what=f"{cls.structure} na={na}, nb={nb}, nk={nk}")
    if template.output_block is not None:
        candidates = _with_output_block(data, template, template.output_block.degree)
    else:
        u, y = _signals(data)
        starts = [_input_and_linear(u, y, template), _linear_start(u, y, template)]
        candidates = [_build(template, s[0], None, s[1], s[2]) for s in starts if s is not None]
    scores = [np.inf if m is None else _score(m, data) for m in candidates]
    return candidates[int(np.argmin(scores))]


def _template(
    cls: type[BlockModel],
    data: Dataset,
    na: int,
    nb: int,
    nk: int,
    r1: int,
    r2: int,
    input_block: Block | None,
) -> BlockModel:
    """A model of the right structure and orders with placeholder parameters."""
    for name, value, low in (("na", na, 0), ("nb", nb, 1), ("nk", nk, 0), ("r1", r1, 1)):
        if not isinstance(value, int | np.integer) or value < low:
            raise OrderError(f"{name} must be a whole number >= {low}, got {value!r}")
    if not isinstance(r2, int | np.integer) or r2 < 1:
        raise OrderError(f"r2 must be a whole number >= 1, got {r2!r}")
    kwargs: dict[str, Any] = dict(na=na, nb=nb, nk=nk, sampling_time=data.sampling_time)
    if cls.requires_input_block:
        if input_block is None:
            if cls is BacklashModel:
                input_block = Backlash(1.0, 0.0, 1.0, 0.0)
            else:
                input_block = TwoSegmentPolynomial(np.zeros(r1 + 1), np.zeros(r1 + 1))
        if not isinstance(input_block, Block):
            raise ParameterError(
                f"input_block must be a block (e.g. TwoSegmentPolynomial), got {input_block!r}"
            )
        kwargs["input_block"] = input_block
    elif input_block is not None:
        raise ParameterError(f"a {cls.structure} model has no input block; drop input_block")
    if cls.requires_output_block:
        kwargs["output_block"] = Polynomial([1.0] + [0.0] * (int(r2) - 1), constant=False)
    if cls in (Hammerstein, HammersteinWiener) and not isinstance(
        kwargs["input_block"], StaticBlock
    ):
        raise ParameterError(
            f"a {cls.structure} model needs a static input block, got {input_block.kind}; "
            "use the backlash structure for a backlash"
        )
    return cls(data.inputs, data.outputs, **kwargs)
