"""One entry point from (structure, method, options) to a checked :class:`FitResult`.

=====================  ==========================================  ==================
structure              methods                                     default
=====================  ==========================================  ==================
arx                    batch, rls, aw-rls, hierarchical-rls        batch
hammerstein            simulation-error, key-term-rls              simulation-error
wiener                 simulation-error, key-term-rls              simulation-error
hammerstein-wiener     simulation-error, key-term-rls              simulation-error
backlash               simulation-error, aw-rls                    simulation-error
=====================  ==========================================  ==================

``refine=True`` follows any method of a block-oriented structure with the refinement on
free-run simulation error, started from that method's estimate.

``center=True`` fits a block-oriented model around the mean operating point of the
estimation data: the means of input and output are subtracted before estimation and
kept in the model as its offsets. It is the default for Wiener models, which have no
constant term anywhere and could not otherwise fit an output that does not vanish with
the input. (ARX handles ``center`` itself.)
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset, Experiment
from blockid.errors import ParameterError
from blockid.fitting.result import FitResult

__all__ = ["STRUCTURES", "METHODS", "DEFAULT_METHOD", "accepted_options", "fit_model"]

METHODS: dict[str, tuple[str, ...]] = {
    "arx": ("batch", "rls", "aw-rls", "hierarchical-rls"),
    "hammerstein": ("simulation-error", "key-term-rls"),
    "wiener": ("simulation-error", "key-term-rls"),
    "hammerstein-wiener": ("simulation-error", "key-term-rls"),
    "backlash": ("simulation-error", "aw-rls"),
}
STRUCTURES = tuple(METHODS)
DEFAULT_METHOD = {s: m[0] for s, m in METHODS.items()}


def _function(structure: str, method: str) -> Callable[..., FitResult]:
    if structure == "arx":
        from blockid.fitting.arx import fit_arx

        return lambda data, **kw: fit_arx(data, method=method, **kw)
    if method == "simulation-error":
        from blockid.fitting.simulation_error import fit_simulation_error

        return lambda data, **kw: fit_simulation_error(data, structure, **kw)
    if method == "key-term-rls":
        from blockid.fitting.key_term import fit_key_term_rls

        return lambda data, **kw: fit_key_term_rls(data, structure, **kw)
    from blockid.fitting.backlash import fit_backlash_aw_rls

    return fit_backlash_aw_rls


#: Options of fit_arx that only some ARX methods use.
_ARX_METHOD_OPTIONS = {
    "batch": set(),
    "rls": {"forgetting", "initial_covariance", "passes", "max_mse_ratio"},
    "aw-rls": {"eps1", "eps2", "initial_covariance", "passes", "max_mse_ratio"},
    "hierarchical-rls": {"forgetting", "initial_covariance", "passes", "max_mse_ratio"},
}
_ARX_COMMON = {"na", "nb", "nk", "center", "allow_unstable"}
#: Block-degree options that a structure without that block cannot use.
_NO_BLOCK_OPTION = {
    "hammerstein": {"r2"},
    "wiener": {"r1"},
    "backlash": {"r1", "r2"},
}


def accepted_options(structure: str, method: str) -> set[str]:
    """Options (orders and settings) that ``structure`` fitted by ``method`` uses."""
    if structure == "arx":
        return _ARX_COMMON | _ARX_METHOD_OPTIONS[method]
    if method == "simulation-error":
        from blockid.fitting.simulation_error import fit_simulation_error as fn
    elif method == "key-term-rls":
        from blockid.fitting.key_term import fit_key_term_rls as fn
    else:
        from blockid.fitting.backlash import fit_backlash_aw_rls as fn
    params = inspect.signature(fn).parameters
    names = {n for n, p in params.items() if p.kind == p.KEYWORD_ONLY or n in ("na", "nb", "nk")}
    return names - _NO_BLOCK_OPTION.get(structure, set())


def fit_model(
    data: Dataset,
    structure: str,
    *,
    method: str | None = None,
    refine: bool = False,
    center: bool | None = None,
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
    refine : bool
        Refine the estimate on free-run simulation error afterwards (block-oriented
        structures).
    center : bool, optional
        Fit around the mean operating point (default: True for Wiener and ARX-free
        structures as described in the module docstring, False otherwise).
    **options
        Orders (``na``, ``nb``, ``nk``, ``r1``, ``r2``) and method settings; an option
        the method does not use is an error, not silently ignored. ``None`` values are
        dropped (the method's default applies).
    """
    if structure not in METHODS:
        raise ParameterError(
            f"unknown structure {structure!r}; choose one of {', '.join(STRUCTURES)}"
        )
    method = method or DEFAULT_METHOD[structure]
    if method not in METHODS[structure]:
        raise ParameterError(
            f"method {method!r} does not apply to {structure}; choose one of "
            f"{', '.join(METHODS[structure])}"
        )
    options = {k: v for k, v in options.items() if v is not None}
    if structure == "arx":
        if center is not None:
            options["center"] = center
    elif center if center is not None else structure == "wiener":
        return _centered(data, structure, method, refine, options)
    accepted = accepted_options(structure, method)
    unused = sorted(set(options) - accepted)
    if unused:
        shown = ", ".join(f"--{u.replace('_', '-')} ({u}=)" for u in unused)
        raise ParameterError(f"{shown} not used by {structure} with method {method}")
    result = _function(structure, method)(data, **options)
    if refine and structure != "arx" and method != "simulation-error":
        from blockid.fitting.simulation_error import refine as refine_fit

        refined = refine_fit(result.model, data)
        refined.settings = {"started_from": result.method, **result.settings, **refined.settings}
        refined.method = f"{result.method}+refine"
        if "theta" in result.history:  # keep the recursive method's trajectories
            refined.history = {
                **refined.history,
                **{
                    k: result.history[k]
                    for k in ("theta", "names", "update")
                    if k in result.history
                },
            }
        result = refined
    if hasattr(result.model, "record_ranges") and not result.model.ranges:
        # (a refinement on simulation error has already recorded them on these data)
        result.model.record_ranges([(e.u, e.y) for e in data.experiments])
    return result


def _centered(
    data: Dataset, structure: str, method: str, refine: bool, options: dict[str, Any]
) -> FitResult:
    """Fit on mean-removed signals; keep the means as the model's offsets."""
    u_off = float(np.mean(np.concatenate([e.u[:, 0] for e in data.experiments])))
    y_off = float(np.mean(np.concatenate([e.y[:, 0] for e in data.experiments])))
    shifted = Dataset(
        data.inputs,
        data.outputs,
        data.sampling_time,
        [Experiment(e.name, e.u - u_off, e.y - y_off) for e in data.experiments],
        data.source,
    )
    result = fit_model(shifted, structure, method=method, refine=refine, center=False, **options)
    result.model = result.model._replace(input_offset=u_off, output_offset=y_off)
    result.model.record_ranges([(e.u, e.y) for e in data.experiments])
    result.settings = {**result.settings, "center": True}
    return result
