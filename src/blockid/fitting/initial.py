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

from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from blockid.blocks.base import Block, LinearFamily
from blockid.blocks.linear import LinearBlock
from blockid.config import get_config
from blockid.data.dataset import Dataset
from blockid.defaults import DEGREE
from blockid.errors import BlockidError, EstimationError, OrderError, ParameterError
from blockid.estimators import BatchLeastSquares
from blockid.fitting.checks import STABILITY_MARGIN, margin_for, simulation_mse, stability_margin
from blockid.models.base import MODEL_TYPES
from blockid.models.block import BlockModel

__all__ = ["absorbed_gain", "initial_estimate", "resolve_structure", "scaled_block"]

#: Rounds of the alternating scheme for models with an output block.
_ROUNDS = 3


def resolve_structure(structure: str | type[BlockModel]) -> type[BlockModel]:
    """The model class of a chain structure name (``"hammerstein-wiener"``) or class:
    one of the :class:`~blockid.models.block.BlockModel` classes (a linear block
    between static blocks), the structures this module starts and
    :func:`~blockid.fitting.simulation_error.fit_simulation_error` refines."""
    known = [name for name, cls in MODEL_TYPES.items() if issubclass(cls, BlockModel)]
    if isinstance(structure, type) and issubclass(structure, BlockModel):
        if structure.structure not in known:
            raise ParameterError(f"{structure.__name__} is not a chain these fits start")
        return structure
    if structure not in known:
        raise ParameterError(
            f"structure={structure!r} is not a chain of one linear block between static "
            f"blocks, which these fits start; choose one of {', '.join(known)} (the others "
            "through fit_model)"
        )
    return MODEL_TYPES[structure]  # type: ignore[return-value]


def scaled_block(block: Block, gain: float) -> Block:
    """The block followed by a ``gain``: ``gain * N(u)`` as a block of its kind.

    Used to move a gain from the linear block into the input block (normalisation
    ``b_0 = 1``). Blocks with positive slopes take positive gains only.
    """
    if not block.linear_in_parameters and not gain > 0:
        raise EstimationError(
            f"cannot absorb the gain {gain:.4g} into a {block.kind} block, whose slopes must "
            "be positive: scale it by the gain's magnitude and keep the sign in the linear "
            "block after it (b_0 = -1; absorbed_gain does both)"
        )
    return block.scaled(gain)


def absorbed_gain(block: Block, gain: float) -> tuple[Block, float]:
    """``gain`` moved into ``block`` as far as its family allows: the block scaled by
    ``gain``, or, for a family whose slopes must be positive (dead zone, saturation,
    backlash, ...) and a negative ``gain``, by ``|gain|``. Returns the block and the
    sign left for the linear block's ``b_0`` (1, or -1: a plant of negative gain keeps
    its sign in the linear block, ``b_0 = -1``, and the block its positive slopes)."""
    if gain < 0 and not block.linear_in_parameters:
        return scaled_block(block, -gain), -1.0
    return scaled_block(block, gain), 1.0


# ----------------------------------------------------------------------------- helpers
def _build(
    like: BlockModel,
    input_block: Block | None,
    output_block: Block | None = None,
    a: np.ndarray | None = None,
    b: np.ndarray | None = None,
) -> BlockModel:
    """A model like ``like`` (class, names, orders, sampling time) with these blocks and
    linear coefficients; a missing block of ``like`` stays missing."""
    g = like.linear
    blocks: list[Block] = []
    if like.input_block is not None:
        blocks.append(input_block)
    blocks.append(LinearBlock(g.na, g.nb, g.nk, a, b, unit_b0=like.input_block is not None))
    if like.output_block is not None:
        blocks.append(output_block)
    return like.with_blocks(blocks, ranges=None)  # type: ignore[return-value]


def _cascade(
    like: BlockModel, block: Block, a: np.ndarray | None = None, b: np.ndarray | None = None
) -> BlockModel:
    """``block`` then a linear block of ``like``'s orders, without output block: to fit an
    input block on its own (also for a Hammerstein-Wiener template)."""
    g = like.linear
    return BlockModel(like.inputs, like.outputs, input_block=block, na=g.na, nb=g.nb, nk=g.nk,
                      a=a, b=b)  # fmt: skip


def _signals(data: Dataset) -> tuple[list[np.ndarray], list[np.ndarray]]:
    return [e.u[:, 0] for e in data.experiments], [e.y[:, 0] for e in data.experiments]


def _lagged(sig: np.ndarray, lag: int, n0: int) -> np.ndarray:
    """``sig(t - lag)`` for ``t = n0 .. N-1``."""
    return sig[n0 - lag : sig.shape[0] - lag]


Chunks = Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]]


def _row_chunks(
    signals: Sequence[tuple[np.ndarray, ...]],
    n0: int,
    build: Callable[..., tuple[np.ndarray, np.ndarray]],
) -> Chunks:
    """Regression rows of every experiment, at most ``regressor_rows``
    (:mod:`blockid.config`) at a time.

    ``signals`` holds one tuple of equally long signals per experiment; ``build`` maps
    slices of them to ``(rows, target)`` for the slice's samples ``n0 ..`` (as for a
    whole experiment). Returns a function that starts a fresh pass over the chunks, so
    that a long record never has all its regressors in memory at once.
    """

    def chunks() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        rows = get_config()["regressor_rows"]
        for parts in signals:
            N = parts[0].shape[0]
            for start in range(n0, N, rows):
                stop = min(start + rows, N)
                yield build(*(p[start - n0 : stop] for p in parts))

    return chunks


def _chunked_least_squares(chunks: Chunks, what: str) -> np.ndarray:
    """QR least squares on RMS-scaled columns (powers of ``u`` differ wildly in scale),
    over chunks of rows, in one pass (:meth:`BatchLeastSquares.fit_chunks`)."""
    try:
        return BatchLeastSquares().fit_chunks(chunks(), normalise=True).coef_
    except EstimationError as exc:
        raise EstimationError(f"initial estimate ({what}): {exc}") from None


def _least_squares(Phi: np.ndarray, target: np.ndarray, what: str) -> np.ndarray:
    """:func:`_chunked_least_squares` of rows held in memory."""
    return _chunked_least_squares(lambda: iter([(Phi, target)]), what)


def _minimum_norm(chunks: Chunks) -> tuple[np.ndarray, float]:
    """``lstsq(G, t)`` over chunks ``(G, t)``, and the residual norm: the triangular
    factor of ``[G | t]`` folded chunk by chunk, then the small system solved."""
    R = None
    for G, t in chunks():
        rows = np.column_stack((G, t))
        R = np.linalg.qr(rows if R is None else np.vstack((R, rows)), mode="r")
    n = R.shape[1] - 1
    v, *_ = np.linalg.lstsq(R[:n, :n], R[:n, n], rcond=None)
    residual = np.hypot(np.linalg.norm(R[:n, :n] @ v - R[:n, n]), np.linalg.norm(R[n:, n]))
    return v, float(residual)


def _stabilise(a: np.ndarray, margin: float = STABILITY_MARGIN) -> np.ndarray:
    """``a`` as it is when its poles lie inside radius ``1 - margin`` (the refinement's
    bound, :func:`~blockid.fitting.checks.stability_margin`); else poles on or outside
    the unit circle moved inside, ``p -> 0.99 / conj(p)``, and every pole at most at
    radius 0.99 (a start for the refinement)."""
    if a.size == 0:
        return a
    poles = np.roots(np.concatenate(([1.0], a)))
    mag = np.abs(poles)
    if np.all(mag < 1.0 - margin):
        return a
    fixed = np.where(mag < 1.0, poles, 0.99 * poles / np.maximum(mag, 1e-300) ** 2)
    fixed = np.where(np.abs(fixed) >= 0.99, 0.99 * fixed / np.abs(fixed), fixed)
    return np.real(np.poly(fixed))[1:]


def _max_lag(na: int, nb: int, nk: int) -> int:
    return max(na, nk + nb - 1, 1)


def _constant_rotation(
    u: Sequence[np.ndarray], basis: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, bool]:
    """Basis change ``T`` with ``(G T)[:, 0] == 1`` when the constant is in span(G),
    ``G = basis(u)`` over all experiments.

    Returns ``(T, True)``, ``T = [v, Q]`` with ``G v = 1`` and ``Q`` an orthonormal
    complement of ``v``; or ``(I, False)`` when the basis does not span constants.
    """

    def rows(ui: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        G = np.asarray(basis(ui), dtype=float)
        return G, np.ones(G.shape[0])

    v, residual = _minimum_norm(_row_chunks([(ui,) for ui in u], 0, rows))
    n, N = v.shape[0], sum(ui.shape[0] for ui in u)
    if residual > 1e-8 * np.sqrt(N):
        return np.eye(n), False
    Q, _ = np.linalg.qr(v[:, None], mode="complete")
    return np.column_stack((v, Q[:, 1:])), True


def _arx_fit(
    w: Sequence[np.ndarray], z: Sequence[np.ndarray], na: int, nb: int, nk: int
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares ARX from ``w`` to ``z`` (``b_0`` free); returns stable ``a`` and ``b``."""
    n0 = _max_lag(na, nb, nk)

    def rows(wi: np.ndarray, zi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        cols = [-_lagged(zi, j, n0) for j in range(1, na + 1)]
        cols += [_lagged(wi, nk + i, n0) for i in range(nb)]
        return np.column_stack(cols), zi[n0:]

    chunks = _row_chunks(list(zip(w, z, strict=True)), n0, rows)
    theta = _chunked_least_squares(chunks, "linear block")
    return _stabilise(theta[:na], margin_for(max(len(x) for x in z))), theta[na:]


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
    T, has_constant = _constant_rotation(u, basis)
    k0 = 1 if has_constant else 0  # columns of G T that vary

    def rows(ui: np.ndarray, zi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        gi = np.asarray(basis(ui), dtype=float) @ T
        cols = [-_lagged(zi, j, n0) for j in range(1, na + 1)]
        if has_constant:
            cols.append(np.ones(zi.shape[0] - n0))
        for i in range(nb):
            cols.extend(_lagged(gi[:, l], nk + i, n0) for l in range(k0, gi.shape[1]))
        return np.column_stack(cols), zi[n0:]

    theta = _chunked_least_squares(_row_chunks(list(zip(u, z, strict=True)), n0, rows), what)
    a = _stabilise(theta[:na], margin_for(max(len(x) for x in z)))
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
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], block: Block, template: BlockModel
) -> tuple[Block, np.ndarray, np.ndarray]:
    """Input block linear in its parameters and linear block, by :func:`_rank_one_fit`."""
    block.check_data(np.concatenate(u))
    vector, a, b = _rank_one_fit(
        u,
        z,
        block.regressors,  # type: ignore[attr-defined]
        template.na,
        template.nb,
        template.nk,
        f"{block.kind} Hammerstein regression",
    )
    return block.with_vector(vector), a, b


def _profile_fit(
    unit: Block, u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> BlockModel | None:
    """ARX from ``w = unit(u)`` to ``z``, its ``b_0`` moved into the block (its sign
    kept in the linear block where the block's slopes must stay positive; None if
    ``b_0`` vanishes)."""
    probe = _cascade(template, unit)
    w = [probe.internal(ui) for ui in u]
    a, b = _arx_fit(w, z, template.na, template.nb, template.nk)
    if not abs(b[0]) > 1e-12 * max(np.max(np.abs(b)), 1e-300):
        return None
    block, sign = absorbed_gain(unit, b[0])
    return _cascade(template, block, a, sign * b / b[0])


def _family_fit(
    family: LinearFamily, u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> BlockModel | None:
    """Rank-one fit of a block family linear in some parameters (None if it fails)."""
    try:
        vector, a, b = _rank_one_fit(
            u, z, family.regressors, template.na, template.nb, template.nk, "block family"
        )
    except (EstimationError, ParameterError):
        return None
    # the factorisation's sign is free: (vector, b) or (-vector, -b), b_0 = -1 then; a
    # family of positive slopes takes the one that builds (a plant of negative gain)
    for sign in (1.0, -1.0):
        try:
            block = family.build(sign * vector)
        except (EstimationError, ParameterError):  # e.g. an edge beyond the data, a slope <= 0
            continue
        return _cascade(template, block, a, sign * b)
    return None


def _candidate(
    shape: Any, u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> BlockModel | None:
    if isinstance(shape, LinearFamily):
        return _family_fit(shape, u, z, template)
    return _profile_fit(shape, u, z, template)


def _grid_search(
    u: Sequence[np.ndarray], z: Sequence[np.ndarray], template: BlockModel
) -> tuple[Block, np.ndarray, np.ndarray]:
    """Profile grid search over the block's shapes (:meth:`Block.initial_grid`), every
    shape completed by least squares and scored by its free-run error on ``z``."""
    block = template.input_block
    u_all = np.concatenate(u)
    grid = block.initial_grid(u_all)
    # shapes with positive slopes (backlash, dead zone, saturation) follow a negative
    # gain with b_0 = -1 (absorbed_gain): the sign lives in the linear block
    if not grid:
        raise ParameterError(
            f"no initial estimate for a {block.kind or type(block).__name__} input block; "
            "pass a starting model (initial=...) to the simulation-error fit"
        )
    candidates = [_candidate(g, u, z, template) for g in grid]
    k = int(np.argmin([_sse(m, u, z) for m in candidates]))
    finer = block.initial_grid(u_all, around=grid[k])
    candidates += [_candidate(g, u, z, template) for g in finer]
    errors = [_sse(m, u, z) for m in candidates]
    best = candidates[int(np.argmin(errors))]
    if best is None:
        raise EstimationError(
            f"initial estimate: no {block.kind} shape fits the data (every candidate's "
            "linear block had b_0 = 0 or its block refused its parameters); check the "
            "input delay nk (a b_0 of zero means nk is too small) or give a starting model "
            "(initial=...)"
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


def _score(model: BlockModel, data: Dataset) -> float:
    try:
        with np.errstate(all="ignore"):
            stable = model.is_stable(stability_margin(data))
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

    def rows(ui: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(block.regressors(ui), dtype=float), ui  # type: ignore[attr-defined]

    chunks = _row_chunks([(ui,) for ui in u], 0, rows)
    v, _ = _minimum_norm(chunks)
    worst = max(float(np.max(np.abs(G @ v - ui), initial=0.0)) for G, ui in chunks())
    if worst > 1e-9 * (max(float(np.max(np.abs(ui), initial=0.0)) for ui in u) + 1e-300):
        return None
    return block.with_vector(b[0] * v), a, b / b[0]


def _output_shape(start: Block, x: Sequence[np.ndarray], y: Sequence[np.ndarray]) -> Block | None:
    """The output block not linear in its parameters (saturation, dead zone, free
    breakpoints) fitted to ``y = N(x)`` over its :meth:`~Block.initial_grid` on the range
    of ``x``: a family by least squares, a fixed shape ``s`` scaled by ``γ = s·y / s·s``
    (kept where ``γ > 0``, which the blocks' positive slopes need); the best static fit,
    or None without a grid. The linear block's gain is left alone: the gain between it
    and the output block is the refinement's to share."""
    xs, ys = np.concatenate(x), np.concatenate(y)
    adapt = getattr(start, "adapted", None)
    block = adapt(xs) if adapt is not None else start
    best, best_sse = None, np.inf
    for shape in block.initial_grid(xs):
        try:
            if isinstance(shape, LinearFamily):
                G = np.asarray(shape.regressors(xs), dtype=float)
                candidate = shape.build(np.linalg.lstsq(G, ys, rcond=None)[0])
            else:
                s = np.asarray(shape(xs), dtype=float)
                gain = float(s @ ys) / float(s @ s) if s @ s > 0 else 0.0
                if not gain > 0:
                    continue
                candidate = shape.scaled(gain)
            with np.errstate(all="ignore"):
                sse = float(np.sum((ys - np.asarray(candidate(xs), dtype=float)) ** 2))
        except (BlockidError, np.linalg.LinAlgError):
            continue
        if sse < best_sse:
            best, best_sse = candidate, sse
    return best


def _with_output_fit(
    model: BlockModel, u: Sequence[np.ndarray], y: Sequence[np.ndarray]
) -> tuple[BlockModel | None, np.ndarray]:
    """Fit the output block from the simulated ``x`` of ``model`` (output block at its
    template) to ``y`` (:meth:`StaticBlock.initial_fit`), its input gain ``g`` moved into
    the linear part (input block or ``b`` times ``g``).

    Returns the model and the simulated ``x' = g x``; None for the model if the block
    has no such fit or ``g <= 0``.
    """
    n0 = model.max_lag
    x = [model.linear.simulate(model.internal(ui)) for ui in u]
    start = model.output_block
    if not start.linear_in_parameters:  # a shape search where the block has a grid
        shaped = _output_shape(start, [xi[n0:] for xi in x], [yi[n0:] for yi in y])
        if shaped is None:
            return None, np.concatenate(x)
        return _build(model, model.input_block, shaped, model.a, model.b), np.concatenate(x)

    def rows(xi: np.ndarray, yi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return start.regressors(xi[n0:]), yi[n0:]  # type: ignore[union-attr]

    chunks = _row_chunks(list(zip(x, y, strict=True)), n0, rows)
    theta = _chunked_least_squares(chunks, f"{start.kind} output block")
    normalised = start.with_vector(theta).normalised_input()
    if normalised is None:
        return None, np.concatenate(x)
    out_block, g = normalised
    if not g > 0:  # dropped as before: the output path keeps its rule (paper B's comparison
        # of structures, docs/reproduction.md, was measured with it)
        return None, np.concatenate(x)
    block, b = model.input_block, model.b
    if block is None:
        b = g * b
    else:
        block = scaled_block(block, g)
    return _build(model, block, out_block, model.a, b), g * np.concatenate(x)


def _with_output_block(data: Dataset, template: BlockModel) -> list[BlockModel]:
    """Candidates of the alternating scheme for Wiener and H-W (module docstring)."""
    u, y = _signals(data)
    start = template.output_block
    fixed = not start.free_mask(True).any()  # e.g. r2 = 1: nothing to alternate with
    candidates: list[BlockModel | None] = []
    linear = _linear_start(u, y, template)
    if linear is not None and template.input_block is not None:
        candidates.append(_build(template, linear[0], start, linear[1], linear[2]))
        if not fixed:
            candidates.append(_with_output_fit(candidates[-1], u, y)[0])
    z = y
    for _ in range(_ROUNDS):
        block, a, b = _input_and_linear(u, z, template)
        candidates.append(_build(template, block, start, a, b))
        if fixed:
            break
        model, x = _with_output_fit(candidates[-1], u, y)
        if model is None:
            break
        candidates.append(model)
        lo, hi = float(np.min(x)), float(np.max(x))
        margin = 0.25 * (hi - lo) + 1e-12
        try:
            z = [model.output_block.inverse_on(yi, (lo - margin, hi + margin)) for yi in y]
        except BlockidError:
            break
    return candidates  # type: ignore[return-value]


# ----------------------------------------------------------------------------- public
def initial_estimate(
    data: Dataset,
    structure: str | type[BlockModel],
    *,
    na: int,
    nb: int,
    nk: int,
    r1: int = DEGREE,
    r2: int = DEGREE,
    input_block: Block | None = None,
    output_block: Block | None = None,
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
        Degree of the default output polynomial (B3), ``y = x + q_2 x^2 + .. + q_r2 x^r2``.
    input_block, output_block : Block, optional
        Templates of the blocks: their kind and form (order, breakpoints) are used,
        their parameter values only as a start where the block has no initial fit (a
        user block's output block). Defaults: ``TwoSegmentPolynomial`` of order ``r1``
        (a ``Backlash`` for the backlash structure) and the identity polynomial of
        degree ``r2``.

    Returns
    -------
    BlockModel
        A model of the structure with a stable linear block, ``b_0 = 1`` with an input
        block and the output block's input gain fixed (``q_1 = 1``).

    Raises
    ------
    EstimationError
        If the data do not determine the parameters (e.g. rank-deficient regression).
    OrderError, ParameterError
        If the orders, the data's signals or the options are invalid.
    """
    cls = resolve_structure(structure)
    template = _template(cls, data, na, nb, nk, r1, r2, input_block, output_block)
    n_par = template.free_parameters().size
    data.check_orders(template.max_lag, n_par, what=f"{cls.structure} na={na}, nb={nb}, nk={nk}")
    if template.output_block is not None:
        candidates = _with_output_block(data, template)
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
    output_block: Block | None,
) -> BlockModel:
    """A model of the right structure and orders with placeholder parameters."""
    for name, value, low in (("na", na, 0), ("nb", nb, 1), ("nk", nk, 0), ("r1", r1, 1)):
        if not isinstance(value, int | np.integer) or value < low:
            raise OrderError(f"{name} must be a whole number >= {low}, got {value!r}")
    if not isinstance(r2, int | np.integer) or r2 < 1:
        raise OrderError(f"r2 must be a whole number >= 1, got {r2!r}")
    default_in, default_out = cls.default_blocks(int(r1), int(r2))
    u_all = np.concatenate([e.u[:, 0] for e in data.experiments])
    blocks = []
    for given, default, what in (
        (input_block, default_in, "input_block"),
        (output_block, default_out, "output_block"),
    ):
        if given is not None and default is None:
            raise ParameterError(
                f"a {cls.structure} model has no {what.replace('_', ' ')}; drop {what}"
            )
        if given is not None and not isinstance(given, Block):
            raise ParameterError(
                f"{what} must be a block (e.g. TwoSegmentPolynomial), got {given!r}"
            )
        blocks.append(given if given is not None else default)
    if blocks[0] is not None:
        blocks[0] = blocks[0].adapted(u_all)
    try:
        return cls.cascade(
            data.inputs,
            data.outputs,
            input_block=blocks[0],
            output_block=blocks[1],
            na=na,
            nb=nb,
            nk=nk,
            sampling_time=data.sampling_time,
        )
    except OrderError as exc:
        raise ParameterError(str(exc)) from None
