"""Identify several structures on the same data and score them on validation data."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from blockid.data.dataset import Dataset
from blockid.errors import EstimationError
from blockid.evaluation.residuals import ResidualAnalysis, residual_check
from blockid.evaluation.validate import ModelOutput, score_model
from blockid.fitting.dispatch import DEFAULT_METHOD, METHODS, accepted_options, fit_model
from blockid.fitting.registry import compared_by_default
from blockid.fitting.result import FitResult

__all__ = ["ModelScore", "CompareResult", "compare_structures"]


@dataclass
class ModelScore:
    """One identified structure and its validation scores (or why it failed), and the
    residual tests of its one-step prediction on the validation data
    (:func:`~blockid.evaluation.residuals.residual_check`; ``residuals_error`` says why
    there are none)."""

    structure: str
    method: str
    fit: FitResult | None
    simulation: ModelOutput | None
    one_step: ModelOutput | None
    error: str | None = None
    one_step_error: str | None = None
    residuals: ResidualAnalysis | None = None
    residuals_error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"structure": self.structure, "method": self.method}
        if self.error:
            out["error"] = self.error
            return out
        out["simulation"] = self.simulation.metrics
        if self.simulation.warnings:
            out["warnings"] = self.simulation.warnings
        out["one_step"] = None if self.one_step is None else self.one_step.metrics
        if self.one_step_error:
            out["one_step_error"] = self.one_step_error
        if self.residuals is not None:
            out["residuals"] = self.residuals.to_dict()
        elif self.residuals_error:
            out["residuals_error"] = self.residuals_error
        out["parameters"] = getattr(self.fit.model, "parameters", None) or (
            self.fit.model.to_dict().get("parameters")
        )
        out["estimation"] = self.fit.estimation_record()
        return out


@dataclass
class CompareResult:
    """Scores of every structure, in the order asked for."""

    models: list[ModelScore] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"models": [m.to_dict() for m in self.models]}

    def ranking(self, output: str, metric: str = "mse") -> list[str]:
        """Structures sorted by a free-run validation metric (failed ones last)."""
        ok = [m for m in self.models if m.simulation is not None]
        key = (
            (lambda m: -m.simulation.metrics[metric][output])
            if metric == "fit_percent"
            else (lambda m: m.simulation.metrics[metric][output])
        )
        return [m.structure for m in sorted(ok, key=key)]


def compare_structures(
    estimation: Dataset,
    validation: Dataset,
    structures: Sequence[str] | None = None,
    *,
    method: str | None = None,
    options: dict[str, Any] | None = None,
) -> CompareResult:
    """Fit each structure on ``estimation`` and score it on ``validation``.

    ``method`` applies to the structures that offer it (others use their default), so
    ``method="key-term-rls"`` compares paper B's four models fitted its way. Options
    (orders ``na, nb, nk, r1, r2`` and method settings) are passed to every structure
    that uses them. A structure whose estimator fails is kept in the result with its
    error message rather than dropped. Each model's residual on ``validation`` is
    tested for whiteness and independence of the inputs, with a one-line verdict
    (``ModelScore.residuals``). ``structures`` default by the data's shape
    (:func:`~blockid.fitting.registry.compared_by_default`): paper B's four on one input
    and one output, else ARX and the linear and polynomial state space.
    """
    if structures is None:
        structures = compared_by_default(estimation.n_inputs, estimation.n_outputs)
    options = dict(options or {})
    result = CompareResult()
    for structure in structures:
        m = method if method in METHODS.get(structure, ()) else DEFAULT_METHOD.get(structure)
        opts = _options_for(structure, m, options)
        try:
            fit = fit_model(estimation, structure, method=m, **opts)
        except EstimationError as exc:
            result.models.append(ModelScore(structure, m, None, None, None, error=str(exc)))
            continue
        sim, one, one_err = score_model(fit.model, validation)
        residuals, why = residual_check(fit.model, validation)
        result.models.append(
            ModelScore(structure, fit.method, fit, sim, one, None, one_err, residuals, why)
        )
    return result


def _options_for(structure: str, method: str, options: dict[str, Any]) -> dict[str, Any]:
    """The shared options this structure and method use (``r1`` is not for ARX, ...)."""
    keep = accepted_options(structure, method)
    return {k: v for k, v in options.items() if k in keep}
