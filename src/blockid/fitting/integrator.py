"""Fits of structures with explicit integrators after their last linear block.

The integrator, ``(1 - z^-1)^n x(k) = w(k - 1)``
(:class:`~blockid.blocks.integrator.Integrator`), has no parameters, so the blocks
before it map ``u`` to ``w(k) = Δ^n y(k + 1)``: they start as the structure's method
fitted to the ``n`` times differenced output (of the structure's ``integrator_start``,
where its own blocks cannot carry the operating point). The chain of those blocks and
the integrator is then refined on the free-run simulation error of ``y`` itself (the
integrator starts from the measured output). The result is a
:class:`~blockid.models.block.ChainModel`: the named cascades hold one linear block.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from blockid.data.dataset import Dataset, Experiment
from blockid.fitting.registry import OPTIONS, STRUCTURES, Structure
from blockid.fitting.result import FitResult

__all__ = ["fit_with_integrator"]

#: Options of the refinement that follows the start.
_REFINEMENT = ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")


def fit_with_integrator(
    decl: Structure,
    method: str,
    data: Dataset,
    order: int,
    options: dict[str, Any],
    run: Callable[[Structure, str, Dataset, dict[str, Any]], FitResult],
) -> FitResult:
    """Fit ``decl`` with ``order`` integrators after its last linear block (module
    docstring); ``run(decl, method, data, options)`` fits the start."""
    from blockid.blocks.integrator import Integrator
    from blockid.fitting.simulation_error import refine
    from blockid.models.block import ChainModel

    t0 = time.perf_counter()
    name, extra = decl.integrator_start or (decl.name, {})
    base = STRUCTURES[name]
    integrator = Integrator(order)
    differenced = Dataset(
        data.inputs,
        data.outputs,
        data.sampling_time,
        [Experiment(e.name, *integrator.differenced(e.u, e.y)) for e in data.experiments],
        data.source,
    )
    accepted = base.accepted(method)
    given = {k: v for k, v in options.items() if k in accepted}
    given.update({k: OPTIONS[k].convert(v) for k, v in extra.items()})
    start = run(base, method, differenced, given).model
    chain = ChainModel(
        data.inputs,
        data.outputs,
        [*start.blocks, integrator],
        sampling_time=data.sampling_time,
        input_offset=start.input_offset,
    )
    t_start = time.perf_counter() - t0
    result = refine(chain, data, **{k: v for k, v in options.items() if k in _REFINEMENT})
    origin = f"{name} fit to the output differenced {order} time(s), then the integrator"
    return replace(
        result,
        settings={**result.settings, "integrator": order, "initial": origin},
        history={**result.history, "initial_seconds": t_start},
    )
