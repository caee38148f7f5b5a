"""One entry point from (structure, method, options) to a checked :class:`FitResult`.

The structures, their methods and every option are declared once, in
:mod:`blockid.fitting.registry`; :func:`fit_model` resolves them there, converts and
checks every option value (text from the command line or a network spec, or Python
values) and runs the method.

``refine=True`` follows any method of a block-oriented structure with the refinement on
free-run simulation error, started from that method's estimate.

``center=True`` fits a block-oriented model around the mean operating point of the
estimation data: the means of input and output are subtracted before estimation and
kept in the model as its offsets. It is the default for Wiener models, which have no
constant term anywhere and could not otherwise fit an output that does not vanish with
the input. (ARX handles ``center`` itself.)
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset, Experiment
from blockid.errors import ParameterError
from blockid.fitting.registry import OPTIONS, STRUCTURES, Structure, get_structure
from blockid.fitting.result import FitResult

__all__ = [
    "STRUCTURES",
    "METHODS",
    "DEFAULT_METHOD",
    "accepted_options",
    "fit_model",
    "resolve_options",
]

#: ``structure -> method names`` (default first), generated from the registry.
METHODS: dict[str, tuple[str, ...]] = {s.name: s.method_names for s in STRUCTURES.values()}
DEFAULT_METHOD = {s.name: s.default_method.name for s in STRUCTURES.values()}


def accepted_options(structure: str, method: str | None) -> set[str]:
    """Options (orders and settings) that ``structure`` fitted by ``method`` uses."""
    return set(get_structure(structure).accepted(method))


def resolve_options(
    structure: str, method: str | None, options: dict[str, Any]
) -> tuple[Structure, str, dict[str, Any]]:
    """Check ``options`` against the registry and convert their values.

    Returns the structure, the method name and the typed options (``None`` values
    dropped: the method's default applies). An option the method does not use is an
    error that lists the ones it does.
    """
    decl = get_structure(structure)
    chosen = decl.method(method)
    given = {k: v for k, v in options.items() if v is not None}
    accepted = decl.accepted(chosen.name)
    unused = [k for k in given if k not in accepted]
    if unused:
        raise ParameterError(
            f"{', '.join(unused)} not used by {structure} with method {chosen.name}; it takes "
            f"{', '.join(accepted)}",
            parameter=unused[0],
        )
    converted = {k: OPTIONS[k].convert(v) for k, v in given.items()}
    return decl, chosen.name, {k: v for k, v in converted.items() if v is not None}


def fit_model(
    data: Dataset,
    structure: str,
    *,
    method: str | None = None,
    **options: Any,
) -> FitResult:
    """Identify a model of the given structure with the given method.

    Parameters
    ----------
    data : Dataset
        Estimation data.
    structure : str
        One of :data:`STRUCTURES`.
    method : str, optional
        One of ``METHODS[structure]``; the default is the converging one.
    **options
        Orders (``na``, ``nb``, ``nk``, ``r1``, ``r2``), blocks (``input_block``,
        ``output_block``: a block or its name), ``center``, ``refine``,
        ``standard_errors`` (parameter covariance into ``settings``) and method
        settings, as declared in :mod:`blockid.fitting.registry`; values may be text.
        An option the method does not use is an error, not silently ignored. ``None``
        values are dropped (the method's default applies).
    """
    decl, method, options = resolve_options(structure, method, options)
    uncertainty = bool(options.pop("standard_errors", False))
    refine = bool(options.pop("refine", False))
    if not decl.block_oriented:
        result = _run(decl, method, data, options)
    else:
        center = options.pop("center", None)
        if center if center is not None else decl.centers(options):
            result = _centered(data, decl, method, refine, options)
        else:
            result = _fit_block(data, decl, method, refine, options)
        if not result.model.ranges:  # the one place ranges are recorded for every method
            model = result.model.with_ranges([(e.u, e.y) for e in data.experiments])
            result = replace(result, model=model)
    from blockid.fitting.checks import linear_block_notes

    notes = linear_block_notes(result.model, data)
    if notes:
        warnings = [*result.settings.get("warnings", []), *notes]
        result = replace(result, settings={**result.settings, "warnings": warnings})
    if uncertainty:
        from blockid.evaluation.uncertainty import with_standard_errors

        result = with_standard_errors(result, data)
    return result


def _run(decl: Structure, method: str, data: Dataset, options: dict[str, Any]) -> FitResult:
    if options.pop("convergence_check", True) is False:
        options["max_mse_ratio"] = None  # the check switched off
    return decl.method(method).run(data, decl.name, options)


def _fit_block(
    data: Dataset, decl: Structure, method: str, refine: bool, options: dict[str, Any]
) -> FitResult:
    result = _run(decl, method, data, options)
    if not refine or method == "simulation-error":
        return result
    from blockid.fitting.simulation_error import refine as refine_fit

    refined = refine_fit(result.model, data)
    history = dict(refined.history)
    for key in ("theta", "names", "update"):  # keep the recursive method's trajectories
        if key in result.history:
            history[key] = result.history[key]
    return replace(
        refined,
        method=f"{result.method}+refine",
        settings={"started_from": result.method, **result.settings, **refined.settings},
        history=history,
    )


def _centered(
    data: Dataset, decl: Structure, method: str, refine: bool, options: dict[str, Any]
) -> FitResult:
    """Fit on mean-removed signals; keep the means as the model's offsets.

    The estimation ranges are relative to the offsets, so those recorded on the shifted
    data hold for the model with offsets unchanged.
    """
    u_off = float(np.mean(np.concatenate([e.u[:, 0] for e in data.experiments])))
    y_off = float(np.mean(np.concatenate([e.y[:, 0] for e in data.experiments])))
    shifted = Dataset(
        data.inputs,
        data.outputs,
        data.sampling_time,
        [Experiment(e.name, e.u - u_off, e.y - y_off) for e in data.experiments],
        data.source,
    )
    result = _fit_block(shifted, decl, method, refine, options)
    model = result.model
    if not model.ranges:
        model = model.with_ranges([(e.u, e.y) for e in shifted.experiments])
    model = model.replace(input_offset=u_off, output_offset=y_off, ranges=model.ranges)
    return replace(result, model=model, settings={**result.settings, "center": True})
