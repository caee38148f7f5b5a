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
into ``J^T J`` in pieces of ``CHUNK`` samples; the directions in which the parameters
are not unique (the state basis, a gain or constant a block shares with the core) are
left alone (``null_space``). A candidate with an eigenvalue of ``A`` outside the circle
of radius ``1 - STABILITY_MARGIN`` or a non-finite or exploding run is rejected.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from blockid.blocks.base import Block, StaticBlock, block_template, channel_specs
from blockid.data.dataset import Dataset
from blockid.errors import ParameterError
from blockid.fitting.result import FitResult
from blockid.fitting.state_space import (
    _check,
    _solver_settings,
    fit_state_space,
    refine_state_space,
)
from blockid.models.block_state_space import BlockStateSpace

__all__ = ["fit_block_state_space", "near_identity"]


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


def near_identity(block: StaticBlock, v: np.ndarray) -> StaticBlock:
    """The block of ``block``'s family nearest the identity on the values ``v`` (least
    squares over every entry, from the block adapted to ``v``)."""
    start = block.adapted(v)
    v = np.asarray(v, dtype=float).ravel()
    if v.size > 20_000:
        v = np.sort(v)[:: v.size // 10_000]
    lo, hi = start.bounds()
    theta0 = np.clip(start.to_vector(), lo, hi)

    def residual(theta: np.ndarray) -> np.ndarray:
        return np.asarray(start.with_vector(theta)(v), dtype=float) - v

    def jac(theta: np.ndarray) -> np.ndarray:
        return start.with_vector(theta).jacobian(v)  # type: ignore[union-attr]

    try:
        sol = least_squares(residual, theta0, jac=jac, bounds=(lo, hi), max_nfev=200)
    except ValueError:  # bounds the solver refuses (an entry fixed by lo == hi): as adapted
        return start
    return start.with_vector(sol.x)  # type: ignore[return-value]


def fit_block_state_space(
    data: Dataset,
    *,
    input_block: Any = None,
    output_block: Any = None,
    nx: int | None = None,
    max_order: int = 10,
    horizon: int | None = None,
    weighting: str = "moesp",
    feedthrough: bool = False,
    max_nfev: int = 100,
    ftol: float = 1e-10,
    xtol: float = 1e-10,
    gtol: float = 1e-10,
) -> FitResult:
    """Static blocks per channel around a linear state-space core (module docstring).

    Parameters
    ----------
    data : Dataset
        One or more inputs and outputs.
    input_block, output_block : str, Block or mapping, optional
        The block of every input (output) channel: one spec for all
        (``"polynomial:degree=3"``), ``"u1=dead-zone,u2=polynomial:degree=3"`` or a
        mapping naming channels (the others pass their signal through). At least one.
    nx, max_order, horizon, weighting, feedthrough
        Of the linear start (:func:`~blockid.fitting.state_space.fit_state_space`).
    max_nfev, ftol, xtol, gtol
        Of each refinement (the linear start's and the block model's).

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
    if all(b is None for b in ins + outs):
        raise ParameterError(
            "a block state-space model needs an input_block or an output_block (without "
            "blocks it is the linear structure 'state-space')",
            parameter="input_block",
        )
    t0 = time.perf_counter()
    linear = fit_state_space(
        data, nx=nx, max_order=max_order, horizon=horizon, weighting=weighting,
        feedthrough=feedthrough, max_nfev=max_nfev, ftol=ftol, xtol=xtol, gtol=gtol,
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
    template = BlockStateSpace(
        data.inputs, data.outputs, lin.A, lin.B, lin.C, lin.D, input_blocks=ins,
        output_blocks=outs, input_offset=lin.input_offset, input_scale=lin.input_scale,
        output_offset=lin.output_offset, output_scale=lin.output_scale,
        sampling_time=lin.sampling_time,
    )  # fmt: skip
    model, info = refine_state_space(
        template, data, initial_states=x0s, feedthrough=feedthrough, max_nfev=max_nfev,
        ftol=ftol, xtol=xtol, gtol=gtol,
    )  # fmt: skip
    # the ranges the blocks' arguments covered, for the extrapolation checks
    zs = [model.run(u, model.initial_state(e.u, e.y[: 4 * model.nx]))[1]
          for u, e in zip(un, data.experiments, strict=True)]  # fmt: skip
    z_all = np.vstack(zs)
    model = model.replace(
        input_range=np.column_stack((u_all.min(axis=0), u_all.max(axis=0))),
        output_range=np.column_stack((z_all.min(axis=0), z_all.max(axis=0))),
    )
    method = f"subspace+block-state-space ({model.kind})"
    metrics = _check(model, data, method)  # type: ignore[arg-type]
    settings = {
        **{k: v for k, v in linear.settings.items() if k != "refinement"},
        **_solver_settings(info, max_nfev),
        "kind": model.kind,
        "input_blocks": [None if b is None else b.kind for b in model.input_blocks],
        "output_blocks": [None if b is None else b.kind for b in model.output_blocks],
        "refinement": info,
        "linear_simulation_metrics": linear.estimation_metrics,
    }
    return FitResult(
        model=model,
        method=method,
        settings=settings,
        estimation_metrics=metrics,
        n_samples=int(sum(e.n_samples for e in data.experiments)),
        history={"seconds": time.perf_counter() - t0},
        metrics_mode="simulation",
    )
