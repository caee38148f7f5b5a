"""Block-oriented models of several inputs and outputs on a linear state-space core
(:class:`~blockid.models.block_state_space.BlockStateSpace`): Hammerstein, Wiener and
Hammerstein-Wiener models with a static block per channel.

**Start.** The linear state-space model of :func:`~blockid.fitting.state_space.
fit_state_space` (subspace, refined on the free-run error), with every block set to
the member of its family nearest the identity on the range its argument spans (least
squares on the normalised input for an input block, on the linear start's output for an
output block; exact for polynomials and piecewise-linear maps): the start *is* the
best linear model, so the fit never ends worse than it, as the PNLSS fit.

**Refinement.** Every free parameter (the core, the biases, the blocks' free entries)
and every experiment's initial state by Levenberg-Marquardt on the free-run simulation
error, with the exact Jacobian walked forward in time
(:meth:`~blockid.models.block_state_space.BlockStateSpace.jacobian_piece`) and summed
into ``J^T J`` in pieces of ``state_space_rows`` samples (:mod:`blockid.config`); the
directions in which the parameters are not unique (the state basis, a gain or constant
a block shares with the core) are left alone (``null_space``). A candidate with an
eigenvalue of ``A`` outside the circle of radius ``1 - margin``
(:func:`~blockid.fitting.checks.stability_margin`) or a non-finite or exploding run is
rejected.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from blockid._kernels import writable
from blockid._kernels.state_space import channel_response
from blockid.blocks.base import Block, StaticBlock, block_template, channel_specs
from blockid.data.dataset import Dataset
from blockid.defaults import (
    MAX_ORDER,
    PATIENCE,
    STATE_SPACE_NFEV,
    STATE_SPACE_TAIL,
    TOLERANCE,
    WEIGHTING,
)
from blockid.errors import ParameterError
from blockid.fitting.result import FitResult
from blockid.fitting.state_space import (
    _refined_from_linear,
    fit_state_space,
    refine_state_space,
)
from blockid.models.block_state_space import BlockStateSpace

__all__ = ["fit_block_state_space", "near_identity", "with_block_ranges"]


def _spec_block(spec: Any, output: bool, where: str) -> StaticBlock | None:
    if spec is None or spec == "" or spec == "none":
        return None
    block = spec if isinstance(spec, Block) else block_template(str(spec), output=output)
    if block.role != "static":
        raise ParameterError(
            f"{where}: {block.kind} is not a static block; a state-space block model takes "
            "static blocks (polynomial, piecewise-linear, dead-zone, saturation, ...)"
        )
    return block


def parse_channel_blocks(spec: Any, channels: list[str], output: bool) -> list[StaticBlock | None]:
    """Blocks per channel from ``spec``: None, one block or spec for every channel
    (``"polynomial:degree=3"``), or blocks named by channel
    (:func:`~blockid.blocks.base.channel_specs`: a mapping, ``"u1=dead-zone"`` or a list
    of such texts; channels not named pass their signal through)."""
    what = "output_block" if output else "input_block"
    named = channel_specs(spec)
    if named is None:
        return [_spec_block(spec, output, what) for _ in channels]
    unknown = [k for k in named if k not in channels]
    if unknown:
        raise ParameterError(
            f"{what} names {unknown}, which are not among the channels {channels}",
            parameter=what,
        )
    return [_spec_block(named.get(c), output, f"{what} {c}") for c in channels]


def near_identity(block: StaticBlock, v: np.ndarray, target: Any = None) -> StaticBlock:
    """The block of ``block``'s family nearest the identity (or the function ``target``)
    on the values ``v`` (least squares over every entry, from the block adapted to
    ``v``)."""
    start = block.adapted(v)
    v = np.asarray(v, dtype=float).ravel()
    if v.size > 20_000:
        v = np.sort(v)[:: v.size // 10_000]
    t = v if target is None else target(v)
    lo, hi = start.bounds()
    theta0 = np.clip(start.to_vector(), lo, hi)

    def residual(theta: np.ndarray) -> np.ndarray:
        return np.asarray(start.with_vector(theta)(v), dtype=float) - t

    def jac(theta: np.ndarray) -> np.ndarray:
        return start.with_vector(theta).jacobian(v)  # type: ignore[union-attr]

    try:
        sol = least_squares(residual, theta0, jac=jac, bounds=(lo, hi), max_nfev=200)
    except ValueError:  # bounds the solver refuses (an entry fixed by lo == hi): as adapted
        return start
    return start.with_vector(sol.x)  # type: ignore[return-value]


#: The loop blocks' starting shapes: each family fitted (least squares) to a soft
#: saturation ``s tanh(v / s)`` and to a soft dead zone ``v - s tanh(v / s)`` with ``s``
#: these fractions of the largest ``|p|`` the linear start gives; the shape whose loop
#: would lower the error most to first order is taken (:func:`_loop_start`).
LOOP_SHAPES = (0.3, 0.6)

#: Samples per experiment on which the loop blocks' starting shapes are compared.
LOOP_START_SAMPLES = 4000


def parse_loop_blocks(spec: Any, outputs: list[str]) -> list[tuple[int, StaticBlock]]:
    """Loop blocks from ``spec``: one spec for a loop per output, or loops named by the
    output each starts from (``"y1=saturation"``, a mapping or a list of such texts).
    Pairs (output index, block)."""
    if spec is None or spec == "" or spec == "none":
        return []
    named = channel_specs(spec)
    if named is None:
        block = _spec_block(spec, False, "loop_block")
        return [(j, block) for j in range(len(outputs))]  # type: ignore[misc]
    unknown = [k for k in named if k not in outputs]
    if unknown:
        raise ParameterError(
            f"loop_block names {unknown}, which are not among the outputs {outputs} (a loop "
            "is named by the output it starts from)",
            parameter="loop_block",
        )
    out = [(j, _spec_block(named.get(c), False, f"loop_block {c}")) for j, c in enumerate(outputs)]
    return [(j, b) for j, b in out if b is not None]


def _modal_directions(A: np.ndarray) -> list[np.ndarray]:
    """Rows ``c`` for which ``c x`` is one mode of ``x(k+1) = A x + ...`` (the real part
    of a left eigenvector; one per real pole or complex pair); none when the
    eigenvectors are nearly dependent."""
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) > 1e8:
        return []
    L = np.linalg.inv(V)
    rows = []
    for i, value in enumerate(lam):
        if value.imag < 0:
            continue  # the pair's other member
        rows.append(np.real(L[i]) if value.imag == 0 else np.real(L[i]) + np.imag(L[i]))
    return rows


def _loop_start(
    template: BlockStateSpace, data: Dataset, x0s: list[np.ndarray], feedthrough: bool
) -> BlockStateSpace:
    """Each loop's starting argument and shape. With the loops open (``Bq = Dq = 0``)
    the model is the linear start, and the first-order effect of opening a loop is the
    span of its ``Bq``, ``Dq`` columns of the Jacobian: the linear core's response to
    the loop block's output ``q = φ(p)`` injected into each state and each output
    (:func:`_injected`). Arguments tried: the loop's output's linear prediction (a
    Lur'e loop) and each mode of the start (:func:`_modal_directions`: the middle of a
    Wiener-Hammerstein path is a filtered input), scaled to unit spread; shapes:
    :data:`LOOP_SHAPES`. Loop by loop, the pair whose columns explain most of the
    start's simulation error beyond the linear model's own columns (and the loops
    already chosen) is kept, each pair once."""
    runs, Js, rs = [], [], []
    names = template.free_parameter_names()
    mask = template.parameter_mask(feedthrough)
    keep = [i for i, n in enumerate(names) if mask[i] and n[0] in "ABCD" and n[1] == "["]
    keep += list(range(mask.size, mask.size + template.nx))  # the initial state's
    for e, x0 in zip(data.experiments, x0s, strict=True):
        n = min(e.n_samples, LOOP_START_SAMPLES)
        u, y = template.normalised_input(e.u[:n]), template.normalised_output(e.y[:n])
        w = template.block_inputs(u)
        X, _, _, z, _ = template._loop_run(w, x0)  # the loops open: the linear start
        with np.errstate(all="ignore"):
            out, J = template.jacobian_piece(u, *template._sensitivity_start(x0))
        Js.append(J[:, keep])
        rs.append((y - out).reshape(-1))
        runs.append((X, w, _output_slopes(template, z)))
    base, r = np.vstack(Js), np.concatenate(rs)
    if not (np.all(np.isfinite(base)) and np.all(np.isfinite(r))):
        return template
    Q = _orthonormal(base)
    r = r - Q @ (Q.T @ r)
    nl = len(template.loop_blocks)
    arguments: list[tuple[np.ndarray, np.ndarray]] = [(template.Cp, template.Dp)]
    for row in _modal_directions(template.A):
        arguments.append((np.tile(row, (nl, 1)), np.zeros_like(template.Dp)))
    shapes = [(f, dz) for f in LOOP_SHAPES for dz in (False, True)]
    used: set[tuple[int, int]] = set()
    picks = []
    for l, family in enumerate(template.loop_blocks):
        best: tuple[float, Any, Any, Any] = (-np.inf, None, None, None)
        for a, (Cp, Dp) in enumerate(arguments):
            ps = [X @ Cp[l] + w @ Dp[l] for X, w, _ in runs]
            spread = max(float(np.concatenate(ps).std()), 1e-12)
            ps = [p / spread for p in ps]
            for k, (fraction, dead_zone) in enumerate(shapes):
                key = (a if a else -1 - l, k)  # the own-output argument differs per loop
                if key in used:
                    continue
                block = _shaped(family, np.concatenate(ps), fraction, dead_zone)
                cols = np.vstack([
                    _injected(template, np.asarray(block(p), dtype=float), slopes)
                    for p, (_, _, slopes) in zip(ps, runs, strict=True)
                ])  # fmt: skip
                if not np.all(np.isfinite(cols)):
                    continue
                cols -= Q @ (Q.T @ cols)
                beta = np.linalg.lstsq(cols, r, rcond=None)[0]
                gain = float(r @ r - np.sum((r - cols @ beta) ** 2))
                if gain > best[0]:
                    best = (gain, key, (Cp[l] / spread, Dp[l] / spread, block), cols)
        if best[1] is None:
            picks.append((template.Cp[l], template.Dp[l], family))
            continue
        used.add(best[1])
        picks.append(best[2])
        extra = _orthonormal(best[3])
        r = r - extra @ (extra.T @ r)
        Q = np.hstack((Q, extra))
    return template.replace(
        Cp=np.array([p[0] for p in picks]),
        Dp=np.array([p[1] for p in picks]),
        loop_blocks=[p[2] for p in picks],
    )


def _orthonormal(M: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the columns' span (singular values above 1e-10 of the
    largest: the linear model's columns are dependent, its state basis not unique)."""
    U, sv, _ = np.linalg.svd(M, full_matrices=False)
    return U[:, sv > 1e-10 * max(float(sv[0]) if sv.size else 0.0, 1e-300)]


def _output_slopes(model: BlockStateSpace, z: np.ndarray) -> np.ndarray:
    """The output blocks' slopes along the core's outputs ``z`` (1 without a block)."""
    slopes = np.ones_like(z)
    for j, b in enumerate(model.output_blocks):
        if b is not None:
            slopes[:, j] = b.derivative(model._at(b, z[:, j], model.output_range[j]))
    return slopes


def _injected(model: BlockStateSpace, q: np.ndarray, slopes: np.ndarray) -> np.ndarray:
    """The outputs' response to ``q`` injected into each state and each core output
    through the linear core (the Jacobian's ``Bq`` and ``Dq`` columns of one loop at
    ``Bq = Dq = 0``), rows ``k * ny + j``, columns the states then the outputs."""
    nx, ny, n = model.nx, len(model.outputs), q.size
    m = nx + ny
    B = np.hstack((np.eye(nx), np.zeros((nx, ny))))
    D = np.hstack((np.zeros((ny, nx)), np.eye(ny)))
    out = np.zeros((n, ny, m))
    G = np.ascontiguousarray(np.repeat(q[:, None], m, axis=1))
    with np.errstate(all="ignore"):
        channel_response(writable(model.A, float), B, writable(model.C, float), D,
                         np.arange(m, dtype=np.int64), G, np.zeros((nx, m)), out)  # fmt: skip
    return (out * slopes[:, :, None]).reshape(n * ny, m)


def _loop_gains(model: BlockStateSpace, p: np.ndarray, q: np.ndarray) -> BlockStateSpace:
    """The same model with each loop block's output scaled to its argument's spread
    (``Bq``, ``Dq`` take the inverse gain): the gain between a loop block and the core
    is not unique, and the fit may leave it anywhere (values of 1e13 with ``Bq`` of
    1e-13 were seen). Blocks that cannot absorb a gain are left as they are."""
    blocks, Bq, Dq = list(model.loop_blocks), model.Bq.copy(), model.Dq.copy()
    for l, b in enumerate(blocks):
        gain = float(np.std(q[:, l]) / max(float(np.std(p[:, l])), 1e-300))
        if not np.isfinite(gain) or gain <= 0.0:
            continue
        try:
            blocks[l] = b.scaled(1.0 / gain)  # type: ignore[assignment]
        except ParameterError:
            continue
        Bq[:, l] *= gain
        Dq[:, l] *= gain
    return model.replace(loop_blocks=blocks, Bq=Bq, Dq=Dq)


def _shaped(block: StaticBlock, p: np.ndarray, fraction: float, dead_zone: bool) -> StaticBlock:
    """``block``'s family fitted to a soft saturation (or soft dead zone) whose knee is
    ``fraction`` of the largest ``|p|`` (:data:`LOOP_SHAPES`)."""
    s = fraction * max(float(np.max(np.abs(p))), 1e-12)

    def target(v: np.ndarray) -> np.ndarray:
        soft = s * np.tanh(v / s)
        return v - soft if dead_zone else soft

    try:
        return near_identity(block, p, target)
    except (ParameterError, ValueError):
        return block


def with_block_ranges(model: BlockStateSpace, data: Dataset) -> BlockStateSpace:
    """``model`` with the ranges its blocks' arguments cover on ``data`` (each experiment
    from the state its first outputs give) recorded for the extrapolation checks, and
    each loop block's gain set by :func:`_loop_gains`."""
    un = [model.normalised_input(e.u) for e in data.experiments]
    x_fit = [model.initial_state(e.u, e.y[: 4 * model.nx]) for e in data.experiments]
    z_all = np.vstack([model.run(u, x0)[1] for u, x0 in zip(un, x_fit, strict=True)])
    u_all = np.vstack(un)
    ranges: dict[str, Any] = {}
    if model.loop_blocks:
        runs = [model._loop_run(model.block_inputs(u), x0) for u, x0 in zip(un, x_fit, strict=True)]
        p, q = np.vstack([r[1] for r in runs]), np.vstack([r[2] for r in runs])
        ranges["loop_range"] = np.column_stack((p.min(axis=0), p.max(axis=0)))
        model = _loop_gains(model, p, q)
    return model.replace(
        input_range=np.column_stack((u_all.min(axis=0), u_all.max(axis=0))),
        output_range=np.column_stack((z_all.min(axis=0), z_all.max(axis=0))),
        **ranges,
    )


def fit_block_state_space(
    data: Dataset,
    *,
    input_block: Any = None,
    output_block: Any = None,
    loop_block: Any = None,
    nx: int | None = None,
    max_order: int = MAX_ORDER,
    horizon: int | None = None,
    weighting: str = WEIGHTING,
    feedthrough: bool = False,
    max_nfev: int = STATE_SPACE_NFEV,
    tail_fraction: float = STATE_SPACE_TAIL,
    patience: int = PATIENCE,
    ftol: float = TOLERANCE,
    xtol: float = TOLERANCE,
    gtol: float = TOLERANCE,
) -> FitResult:
    """Static blocks per channel around a linear state-space core (module docstring).

    Parameters
    ----------
    data : Dataset
        One or more inputs and outputs.
    input_block, output_block : str, Block or mapping, optional
        The block of every input (output) channel: one spec for all
        (``"polynomial:degree=3"``), ``"u1=dead-zone,u2=polynomial:degree=3"`` or a
        mapping naming channels (the others pass their signal through).
    loop_block : str, Block or mapping, optional
        Static blocks inside the core's loop (:class:`BlockStateSpace`: ``q = φ(p)``,
        ``p = Cp x + Dp w``): one spec for a loop per output, or loops named by the
        output each starts from (``"y1=saturation"``). Each loop starts open (``Bq = Dq
        = 0``) from its output's linear prediction (``Cp``, ``Dp`` the start's ``C``,
        ``D`` row), with the shape :func:`_loop_start` picks. At least one block of the
        three kinds.
    nx, max_order, horizon, weighting, feedthrough
        Of the linear start (:func:`~blockid.fitting.state_space.fit_state_space`).
    max_nfev, tail_fraction, patience, ftol, xtol, gtol
        Of each refinement (the linear start's and the block model's; early stopping
        on a held-back tail: :func:`~blockid.fitting.state_space_refinement.refine_state_space`).

    Returns
    -------
    FitResult
        ``metrics_mode = "simulation"``; ``settings`` has the start's order and metrics.

    Examples
    --------
    A cubic on the first of two inputs of a first-order plant; the second input passes
    straight through:

    >>> import numpy as np
    >>> from blockid.blocks import Polynomial
    >>> from blockid.data import Dataset
    >>> cubic = Polynomial([0.0, 1.0, 0.0, 0.5])
    >>> plant = BlockStateSpace(["a", "b"], ["y"], A=[[0.8]], B=[[1.0, 0.5]], C=[[1.0]],
    ...                         D=[[0.0, 0.0]], input_blocks={"a": cubic})
    >>> u = np.random.default_rng(0).uniform(-1, 1, (1000, 2))
    >>> data = Dataset.from_arrays(u, plant.simulate(u), ["a", "b"], ["y"])
    >>> fit = fit_block_state_space(data, nx=1, input_block={"a": "polynomial:degree=3"})
    >>> fit.model.kind, round(fit.estimation_metrics["fit_percent"]["y"], 1)
    ('hammerstein', 100.0)
    """
    ins = parse_channel_blocks(input_block, list(data.inputs), output=False)
    outs = parse_channel_blocks(output_block, list(data.outputs), output=True)
    loops = parse_loop_blocks(loop_block, list(data.outputs))
    if all(b is None for b in ins + outs) and not loops:
        raise ParameterError(
            "a block state-space model needs an input_block, an output_block or a "
            "loop_block (without blocks it is the linear structure 'state-space')",
            parameter="input_block",
        )
    t0 = time.perf_counter()
    linear = fit_state_space(
        data, nx=nx, max_order=max_order, horizon=horizon, weighting=weighting,
        feedthrough=feedthrough, max_nfev=max_nfev, tail_fraction=tail_fraction,
        patience=patience, ftol=ftol, xtol=xtol, gtol=gtol,
    )  # fmt: skip
    lin = linear.model
    un = [lin.normalised_input(e.u) for e in data.experiments]
    x0s = [lin.initial_state(e.u, e.y[: 4 * lin.nx]) for e in data.experiments]
    z = np.vstack([lin.run(u, x0)[0] for u, x0 in zip(un, x0s, strict=True)])
    u_all = np.vstack(un)
    for i, b in enumerate(ins):
        if b is not None:
            b.check_data(u_all[:, i])
            ins[i] = near_identity(b, u_all[:, i])
    for j, b in enumerate(outs):
        if b is not None:
            outs[j] = near_identity(b, z[:, j])
    rows = [j for j, _ in loops]
    template = BlockStateSpace(
        data.inputs, data.outputs, lin.A, lin.B, lin.C, lin.D, input_blocks=ins,
        output_blocks=outs, input_offset=lin.input_offset, input_scale=lin.input_scale,
        output_offset=lin.output_offset, output_scale=lin.output_scale,
        sampling_time=lin.sampling_time, loop_blocks=[b for _, b in loops],
        Cp=lin.C[rows], Dp=lin.D[rows],
    )  # fmt: skip
    if loops:
        template = _loop_start(template, data, x0s, feedthrough)
    model, info = refine_state_space(
        template, data, initial_states=x0s, feedthrough=feedthrough, max_nfev=max_nfev,
        tail_fraction=tail_fraction, patience=patience, ftol=ftol, xtol=xtol, gtol=gtol,
    )  # fmt: skip
    model = with_block_ranges(model, data)
    own = {
        "kind": model.kind,
        "input_blocks": [None if b is None else b.kind for b in model.input_blocks],
        "output_blocks": [None if b is None else b.kind for b in model.output_blocks],
        "loop_blocks": [b.kind for b in model.loop_blocks],
    }
    method = f"subspace+block-state-space ({model.kind})"
    return _refined_from_linear(model, data, method, linear, info, max_nfev, own, t0)
