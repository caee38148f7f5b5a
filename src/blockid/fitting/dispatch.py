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
the input, and for blocks anchored at their signal's zero whose signal does not take
both signs (:func:`default_centring`). (ARX handles ``center`` itself.)
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import EstimationError, ParameterError
from blockid.fitting.checks import refuse_constant_inputs
from blockid.fitting.registry import (
    STRUCTURES,
    Structure,
    get_structure,
    resolve_options,
)
from blockid.fitting.result import FitResult, simulation_result

__all__ = [
    "STRUCTURES",
    "METHODS",
    "DEFAULT_METHOD",
    "accepted_options",
    "climb_from",
    "fit_model",
    "refine_from",
    "resolve_options",
    "default_centring",
    "run_method",
    "takes_both_signs",
]

#: ``structure -> method names`` (default first), generated from the registry.
METHODS: dict[str, tuple[str, ...]] = {s.name: s.method_names for s in STRUCTURES.values()}
DEFAULT_METHOD = {s.name: s.default_method.name for s in STRUCTURES.values()}


def accepted_options(structure: str, method: str | None) -> set[str]:
    """Options (orders and settings) that ``structure`` fitted by ``method`` uses."""
    return set(get_structure(structure).accepted(method))


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
    decl, method, options = _checked(data, structure, method, options)
    uncertainty = bool(options.pop("standard_errors", False))
    refine = bool(options.pop("refine", False))
    if not decl.block_oriented:
        result = _run(decl, method, data, options)
    else:
        center = options.pop("center", None)
        if center if center is not None else default_centring(decl, options, data):
            result = _centered(data, decl, method, refine, options)
        else:
            try:
                result = _fit_block(data, decl, method, refine, options)
            except EstimationError as exc:
                hint = _centring_hint(options)
                if not hint:
                    raise
                hinted = EstimationError(f"{exc}{hint}")
                hinted.__dict__.update(exc.__dict__)  # e.g. the trajectories up to a failure
                raise hinted from None
        # the one place ranges are recorded for every method of a chain (a block model
        # of several inputs, key-term RLS's, records its own)
        if hasattr(result.model, "with_ranges") and not result.model.ranges:
            model = result.model.with_ranges([(e.u, e.y) for e in data.experiments])
            result = replace(result, model=model)
    return _finish(result, data, structure, uncertainty)


def _checked(
    data: Dataset, structure: str, method: str | None, options: dict[str, Any]
) -> tuple[Any, str, dict[str, Any]]:
    """The structure's declaration, the method and the converted options of a fit on
    ``data``, checked before any work (:func:`fit_model` and :func:`climb_from` alike)."""
    decl, method, options = resolve_options(structure, method, options)
    for key in ("input_block", "output_block"):
        if decl.block_oriented and isinstance(options.get(key), dict):
            raise ParameterError(
                f"{key}: blocks per channel ({', '.join(options[key])}) are for a model of "
                f"several inputs or outputs (structure block-state-space); {decl.name} takes "
                "one block",
                parameter=key,
            )
    _check_orders_fit(data, decl.name, options)
    refuse_constant_inputs(data)
    return decl, method, options


def climb_from(model: Any, done: int, data: Dataset, structure: str, **options: Any) -> FitResult:
    """:func:`fit_model` ``(data, structure, **options)`` of a polynomial state space fitted
    degree by degree (``start_degree`` below ``degree``), continued from ``model``: the
    fit of the same options up to degree ``done`` on the same ``data``. Only the rungs
    above ``done`` are refined
    (:func:`~blockid.fitting.state_space.continue_polynomial_state_space`), and the
    options and the result are checked as :func:`fit_model` checks them, so the model
    is the whole fit's, bit for bit, or the same error is raised."""
    from blockid.fitting.state_space import continue_polynomial_state_space

    decl, method, options = _checked(data, structure, None, options)
    if "start_degree" not in decl.accepted(method):
        raise ParameterError(
            f"climb_from continues a polynomial state space fitted degree by degree, not "
            f"{structure}",
            parameter="structure",
        )
    options.pop("standard_errors", None)
    options.pop("refine", None)
    if options.pop("integrator", 0):
        raise ParameterError(
            "climb_from continues a fit without integrators", parameter="integrator"
        )
    result = continue_polynomial_state_space(model, data, done, **options)
    return _finish(result, data, structure, False)


def refine_from(model: Any, data: Dataset, structure: str, **options: Any) -> FitResult:
    """``model``, a fit of ``structure`` (on other data: a part of ``data``, say), refined
    on ``data``'s free-run simulation error and checked as :func:`fit_model` checks.

    The model keeps its form: orders, blocks, integrators and its offsets (a centred fit
    keeps the means of the data it was fitted on as its operating point). ``options``
    are the fit's options (as given to :func:`fit_model`); the refinement's own
    (``max_nfev``, ``tail_fraction``, ``patience``, tolerances, ``feedthrough``) apply
    and the rest, which shaped the start, are ignored; a polynomial state space fitted
    degree by degree is refined with its top degree's limit (``rung_nfev``). The ranges
    of the internal signals are recorded on ``data``. ``identify`` refines each fold's
    model on all the estimation data this way when the direct fit falls short of the
    folds.
    """
    from blockid.fitting.simulation_error import refine

    decl, method, options = resolve_options(structure, None, options)
    if method != "simulation-error":
        raise ParameterError(
            f"refine_from continues a simulation-error fit; {structure} is fitted by {method}",
            parameter="structure",
        )
    tolerances = {
        k: options[k]
        for k in ("max_nfev", "tail_fraction", "patience", "ftol", "xtol", "gtol")
        if k in options
    }
    if options.get("rung_nfev") is not None:  # a climbed fit: its top degree's limit
        tolerances["max_nfev"] = options["rung_nfev"]
    if not decl.block_oriented:  # the state-space structures, with the fits' defaults
        from blockid.defaults import PATIENCE, STATE_SPACE_TAIL
        from blockid.fitting.block_state_space import with_block_ranges

        tolerances.setdefault("tail_fraction", STATE_SPACE_TAIL)
        polynomial = getattr(model, "n_monomials", 0) > 0
        tolerances.setdefault("patience", None if polynomial else PATIENCE)
        from blockid.fitting.state_space import (
            _check,
            _solver_settings,
            refine_state_space,
            with_observed_range,
        )
        from blockid.models.block_state_space import BlockStateSpace

        fitted, info = refine_state_space(
            model, data, feedthrough=bool(options.get("feedthrough", False)), **tolerances
        )
        if isinstance(fitted, BlockStateSpace):
            fitted = with_block_ranges(fitted, data)
        elif np.isfinite(np.asarray(model.observed_lower)).any():  # its monomials' range
            fitted = with_observed_range(fitted, data)
        how = f"{structure} refined from a given model"
        settings = {
            **_solver_settings(info, int(tolerances.get("max_nfev", 100))),
            "refinement": info,
            **({"warnings": info["warnings"]} if info.get("warnings") else {}),
        }
        metrics = _check(fitted, data, how)
        result = simulation_result(
            fitted, data, how, settings, metrics, {"seconds": info["seconds"]}
        )
    else:
        result = refine(model, data, **tolerances)
    result = replace(result, settings={**result.settings, "initial": "given model"})
    return _finish(result, data, structure, False)


def _finish(result: FitResult, data: Dataset, structure: str, uncertainty: bool) -> FitResult:
    """A fit's last checks: a finite error; notes on its linear blocks, its run from
    rest, its poles, its output's range, its degenerate blocks and its refinement's
    stop (:mod:`blockid.fitting.checks`)."""
    mse = result.estimation_metrics.get("mse", {})
    if not all(np.isfinite(v) for v in mse.values()):
        raise EstimationError(
            f"the {structure} fit's error on the estimation data is not finite (MSE "
            f"{', '.join(f'{k}: {v}' for k, v in mse.items())}): the signals or the model "
            "overflow; rescale the signals (to SI units, or by their typical size) and fit "
            "again"
        )
    from blockid.fitting.checks import (
        degenerate_block_notes,
        linear_block_notes,
        output_range_warnings,
        pole_warnings,
        rest_notes,
    )

    model = result.model
    integrating = [s.name for s in STRUCTURES.values() if "integrator" in s.accepted(None)]
    notes = linear_block_notes(model, data, integrating) + rest_notes(model, data)
    notes += pole_warnings(model, data) + output_range_warnings(model, data)
    notes += degenerate_block_notes(model) + _evaluation_limit_notes(result)
    if notes:
        warnings = [*result.settings.get("warnings", []), *notes]
        result = replace(result, settings={**result.settings, "warnings": warnings})
    if uncertainty:
        from blockid.evaluation.uncertainty import with_standard_errors

        result = with_standard_errors(result, data)
    return result


def _evaluation_limit_notes(result: FitResult) -> list[str]:
    """A note when the (last) refinement stopped at its evaluation limit, not converged."""
    settings = result.settings
    if "max_nfev" not in str(settings.get("stop_reason", "")):
        return []
    if settings.get("best_tail_earlier"):  # early stopping returned an earlier iterate:
        return []  # the held-back tails got worse after it, more evaluations would not help
    limit = settings.get("max_nfev")
    return [
        f"the refinement stopped at its evaluation limit (max_nfev = {limit}, "
        f"{settings.get('iterations', '?')} iterations) before it converged: the model may "
        "improve with a larger --max-nfev"
    ]


def run_method(decl: Structure, method: str, data: Dataset, options: dict[str, Any]) -> FitResult:
    """Run ``method`` of structure ``decl`` on ``data`` with converted ``options``: the
    registry's ``target`` function, given ``structure``/``method`` where it takes them,
    or the integrator fit (:mod:`blockid.fitting.integrator`) when ``integrator > 0``."""
    options = dict(options)
    integrations = options.pop("integrator", 0)
    if integrations:
        from blockid.fitting.integrator import fit_with_integrator

        return fit_with_integrator(decl, method, data, integrations, options, run_method)
    chosen = decl.method(method)
    extra = {"structure": decl.name, "method": chosen.name}
    extra = {k: v for k, v in extra.items() if k in chosen.passes}
    return chosen.function()(data, **extra, **options)


def _check_orders_fit(data: Dataset, structure: str, options: dict[str, Any]) -> None:
    """Refuse orders the data cannot hold, before any work (an ``na`` of 10^11 asked for
    745 GiB; one of 1000 on 300 samples ran for half a minute and then blamed the
    data): every experiment must be longer than the longest lag, and all together give
    a regression row per coefficient."""
    orders = {k: np.asarray(options[k]) for k in ("na", "nb", "nk") if k in options}
    if "nx" in options:
        orders["nx"] = np.asarray(options["nx"])
    if not orders:
        return
    top = {k: int(v.max()) if v.size else 0 for k, v in orders.items()}
    lag = max(top.get("na", 0), top.get("nb", 1) + top.get("nk", 0) - 1, top.get("nx", 0))
    n = max(top.get("na", 0) + top.get("nb", 0), top.get("nx", 0) ** 2, 1)
    shown = ", ".join(f"{k}={options[k]}" for k in ("na", "nb", "nk", "nx") if k in options)
    data.check_orders(lag, n, what=f"{structure} with {shown}")


def takes_both_signs(values: np.ndarray) -> bool:
    """At least 5 % of the samples on each side of zero."""
    values = np.asarray(values, dtype=float)
    return bool(np.mean(values < 0) >= 0.05 and np.mean(values > 0) >= 0.05)


def default_centring(decl: Structure, options: dict[str, Any], data: Dataset) -> bool:
    """Whether a fit of ``decl`` with converted ``options`` and no ``center`` is centred.

    * never, with a block placed at given values of its signal (``Block.centred`` False:
      a piecewise-linear map with given breakpoints);
    * with anchored blocks (``Block.anchored``: a dead zone, a saturation, a two-segment
      polynomial, whose form sits at its signal's zero), centred exactly when none of
      their signals (the input for an input block, the output for an output or a
      feedback block) takes both signs: a 2-10 V output has no use for a saturation
      centred at 0 V, a valve current of both signs has its break at 0 A;
    * otherwise the structure's default (``center_default``).
    """
    from blockid.blocks.base import Block

    roles = {option: role for role, option in decl.slots}
    blocks = [(k, v) for k, v in options.items() if isinstance(v, Block)]
    if any(not v.centred for _, v in blocks):
        return False
    anchored = [roles.get(k, "input") for k, v in blocks if v.anchored]
    if not anchored:
        return decl.center_default
    column = {"input": lambda e: e.u[:, 0], "output": lambda e: e.y[:, 0]}
    for role in anchored:
        signal = np.concatenate([column["input" if role == "input" else "output"](e)
                                 for e in data.experiments])  # fmt: skip
        if takes_both_signs(signal):
            return False
    return True


def _centring_hint(options: dict[str, Any]) -> str:
    """What to try when an uncentred fit with a block anchored at its signal's zero (or
    at given values) failed: centring, which the default left off."""
    from blockid.blocks.base import Block

    blocks = [v for v in options.values() if isinstance(v, Block) and (v.anchored or not v.centred)]
    if not blocks:
        return ""
    kinds = ", ".join(sorted({b.kind for b in blocks}))
    return (
        f". The fit was not centred (the {kinds} block sits at its signal's own zero or "
        "values): if the plant's nonlinearity sits at the operating point instead, try "
        "center=True (--center true)"
    )


def _run(decl: Structure, method: str, data: Dataset, options: dict[str, Any]) -> FitResult:
    if options.pop("convergence_check", True) is False:
        options["max_mse_ratio"] = None  # the check switched off
    return run_method(decl, method, data, options)


def _fit_block(
    data: Dataset, decl: Structure, method: str, refine: bool, options: dict[str, Any]
) -> FitResult:
    if refine and data.n_inputs > 1 and method != "simulation-error":
        raise ParameterError(
            "refine continues a chain of one input on its free-run error; a model of "
            "several inputs (key-term RLS's block state space, whose core realises the "
            "linear block with many states) is not refined: fit structure "
            "block-state-space with method simulation-error instead",
            parameter="refine",
        )
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
    if data.n_inputs > 1:  # key-term RLS of several inputs: a block state-space model
        u_off = np.vstack([e.u for e in data.experiments]).mean(axis=0)
        y_off = np.vstack([e.y for e in data.experiments]).mean(axis=0)
    else:
        u_off = float(np.mean(np.concatenate([e.u[:, 0] for e in data.experiments])))
        y_off = float(np.mean(np.concatenate([e.y[:, 0] for e in data.experiments])))
    shifted = data.shifted(u_off, y_off)
    result = _fit_block(shifted, decl, method, refine, options)
    model = result.model
    if not hasattr(model, "with_ranges"):  # its ranges are of the normalised signals
        model = model.replace(input_offset=u_off, output_offset=y_off)
        return replace(result, model=model, settings={**result.settings, "center": True})
    if not model.ranges:
        model = model.with_ranges([(e.u, e.y) for e in shifted.experiments])
    # the fit's own output offset (a Wiener model refines it) on top of the mean
    y_off = y_off + model.output_offset
    model = model.replace(input_offset=u_off, output_offset=y_off, ranges=model.ranges)
    return replace(result, model=model, settings={**result.settings, "center": True})
