"""A model's parameter table: every estimated parameter with its value and, when the fit
carries them, its standard error.

The parameters are those a fit estimates: ``free_parameters()`` under
``free_parameter_names()`` (block-oriented, feedback and state-space models), or every
output's ``parameter_vector`` under ``parameter_names`` (ARX). The standard errors come
from the fit's ``settings["covariance"]`` (the square roots of its diagonal, written by
:func:`blockid.evaluation.uncertainty.with_standard_errors`) or, without it, from
``settings["standard_errors"]`` (:func:`blockid.plotting.uncertainty.free_standard_errors`).
An infinite standard error means the data did not determine the parameter.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.plotting.uncertainty import _flatten, free_standard_errors

__all__ = ["ParameterTable", "parameter_table"]


@dataclass(frozen=True)
class ParameterTable:
    """Names, values and standard errors (None: the fit carries none) of a model's
    estimated parameters, and what else a reader needs to read them."""

    names: list[str]
    values: np.ndarray
    standard_errors: np.ndarray | None
    source: str  # where the standard errors come from ("" without them)
    n_fixed: int  # numbers of the model's parameters fixed by the normalisation
    operating_point: dict[str, float]  # offsets subtracted before the model, by signal

    #: The header of :meth:`rows`.
    HEADER = ("parameter", "value", "standard error", "relative SE [%]")

    def rows(self) -> list[list[Any]]:
        """``[name, value, standard error, relative standard error in %]`` per parameter
        (text where a number is not defined)."""
        out = []
        for k, (name, value) in enumerate(zip(self.names, self.values, strict=True)):
            if self.standard_errors is None:
                out.append([name, float(value), "n/a", "n/a"])
                continue
            se = float(self.standard_errors[k])
            if not np.isfinite(se):
                out.append([name, float(value), "not determined", ""])
                continue
            rel = 100.0 * se / abs(value) if value != 0 else float("inf")
            out.append([name, float(value), se, float(f"{rel:.3g}") if np.isfinite(rel) else ""])
        return out

    def notes(self) -> list[str]:
        """Sentences that say what the table does not show."""
        out = []
        if self.standard_errors is None:
            out.append(
                "No standard errors: the fit carries none (fit with standard_errors=True, "
                "or --standard-errors on the command line)."
            )
        else:
            out.append(f"Standard errors: {self.source}.")
        if self.n_fixed:
            out.append(
                f"{self.n_fixed} parameter(s) of the model are fixed by the normalisation "
                "of the cascade (such as b_0 = 1 after an input block and q_1 = 1 in an "
                "output polynomial): not estimated, so not listed."
            )
        if self.operating_point:
            shown = ", ".join(f"{k} {v:.6g}" for k, v in self.operating_point.items())
            out.append(f"Operating point subtracted before the model (not estimated): {shown}.")
        return out


def _names_and_values(model: Any) -> tuple[list[str], np.ndarray]:
    if hasattr(model, "free_parameter_names"):
        return list(model.free_parameter_names()), np.asarray(model.free_parameters(), float)
    if hasattr(model, "parameter_names"):  # ARX: the outputs one after another
        outputs = range(len(model.outputs))
        names = [n for i in outputs for n in model.parameter_names(i)]
        values = [np.asarray(model.parameter_vector(i), float) for i in outputs]
        return names, np.concatenate(values) if values else np.zeros(0)
    return [], np.zeros(0)


def _from_covariance(fit: Any, names: list[str]) -> np.ndarray | None:
    settings = getattr(fit, "settings", None)
    record = settings.get("covariance") if isinstance(settings, Mapping) else None
    if not isinstance(record, Mapping) or list(record.get("names", ())) != names:
        return None
    diagonal = [row[k] for k, row in enumerate(record["matrix"])]
    return np.sqrt(np.abs([np.inf if v is None else float(v) for v in diagonal]))


def _standard_errors(fit: Any, names: list[str]) -> tuple[np.ndarray | None, str]:
    if fit is None:
        return None, ""
    se = _from_covariance(fit, names)
    if se is not None:
        basis = str(fit.settings["covariance"].get("basis", "")).strip()
        return se, "from the parameter covariance" + (f"; its basis: {basis}" if basis else "")
    se = free_standard_errors(fit)
    if se is None:  # ARX: a mapping shaped like its coefficients, outputs in order
        raw = (getattr(fit, "settings", None) or {}).get("standard_errors")
        flat = np.asarray(_flatten(raw) if raw is not None else [], float)
        se = flat if flat.size == len(names) and np.all(flat >= 0) else None
    return se, "as the fit records them (settings['standard_errors'])" if se is not None else ""


def _n_numbers(model: Any) -> int:
    parameters = getattr(model, "parameters", None)
    return len(_flatten(parameters)) if isinstance(parameters, Mapping) else 0


def _operating_point(model: Any) -> dict[str, float]:
    out = {}
    for names, attr in (("inputs", "input_offset"), ("outputs", "output_offset")):
        values = np.atleast_1d(np.asarray(getattr(model, attr, 0.0), float)).reshape(-1)
        for name, value in zip(getattr(model, names, ()), values, strict=False):
            if value != 0.0:
                out[str(name)] = float(value)
    return out


def parameter_table(model: Any, fit: Any = None) -> ParameterTable:
    """The parameter table of ``model``, with the standard errors ``fit`` carries.

    >>> from blockid.blocks import Polynomial
    >>> from blockid.models import Hammerstein
    >>> m = Hammerstein("u", "y", input_block=Polynomial([0.0, 1.0, 0.5]),
    ...                 na=1, nb=2, nk=1, a=[-0.5], b=[1.0, 0.2])
    >>> t = parameter_table(m)
    >>> t.names, t.values.tolist(), t.n_fixed
    (['f_0', 'f_1', 'f_2', 'a_1', 'b_1'], [0.0, 1.0, 0.5, -0.5, 0.2], 1)
    """
    names, values = _names_and_values(model)
    se, source = _standard_errors(fit, names)
    if se is not None and se.size != values.size:
        se, source = None, ""
    n_fixed = max(_n_numbers(model) - values.size, 0) if hasattr(model, "blocks") else 0
    return ParameterTable(names, values, se, source, n_fixed, _operating_point(model))
