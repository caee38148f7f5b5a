"""What ``identify`` scores and returns: a candidate's score on one fold
(:class:`FoldScore`), over the folds (:class:`Score`), and the search's result
(:class:`IdentifyResult`); :mod:`blockid.workflows.identify` makes them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from blockid.evaluation.trust import Trust
from blockid.workflows.search_space import Candidate

__all__ = ["FoldScore", "IdentifyResult", "Score"]


# ----------------------------------------------------------------------------- scores
@dataclass(frozen=True)
class FoldScore:
    """One candidate on one fold: its free-run RMSE there, or why it failed."""

    rmse: float = math.inf  # data units, pooled over the outputs
    relative: float = math.inf  # rmse / the fold's output spread
    n_parameters: int = 0
    reason: str = ""
    trust: Trust | None = None
    seconds: float = 0.0
    #: the fold's model, of a candidate a climb may continue (taken off by the search)
    model: Any = None


@dataclass
class Score:
    """A candidate's result over the folds (or why it was rejected)."""

    candidate: Candidate
    stage: str
    folds: list[FoldScore] = field(default_factory=list)
    rmse: float = math.inf
    fit_percent: float = -math.inf
    n_parameters: int = 0
    reason: str = ""
    flags: list[str] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.reason

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "structure": self.candidate.structure,
            "options": _jsonable(self.candidate.options),
            "stage": self.stage,
            "seconds": round(self.seconds, 3),
        }
        if self.reason:
            out["rejected"] = self.reason
        else:
            out.update(
                cv_rmse=self.rmse,
                cv_fit_percent=self.fit_percent,
                fold_rmse=[f.rmse for f in self.folds],
                n_parameters=self.n_parameters,
            )
        if self.flags:
            out["flags"] = list(self.flags)
        return out


def _jsonable(options: dict[str, Any]) -> dict[str, Any]:
    def plain(v: Any) -> Any:
        if isinstance(v, int | float | str | bool):
            return v
        return [plain(x) for x in v] if isinstance(v, tuple) else str(v)

    return {k: plain(v) for k, v in options.items()}


@dataclass(frozen=True)
class IdentifyResult:
    """What :func:`identify` chose and everything it tried.

    Attributes
    ----------
    selected : Score
        The chosen candidate (its cross-validation score).
    fit : FitResult
        The chosen candidate fitted on all estimation data; ``fit.model`` is the model.
    ranked : list of Score
        Candidates that were scored, best first (the selected one first).
    rejected : list of Score
        Candidates that failed, with their reasons.
    simulation, one_step : ModelOutput or None
        Scores of the model on the validation data (or on the estimation data when no
        validation data were given: see ``on``).
    on : str
        ``"validation"`` or ``"estimation"``.
    seconds : float
    holdout : str
        How the estimation data were cut into folds.
    search : dict
        Effort, jobs, rule, folds, stages, whether the time limit cut the search.
    """

    selected: Score
    fit: Any
    ranked: list[Score]
    rejected: list[Score]
    simulation: Any
    one_step: Any
    one_step_error: str | None
    on: str
    seconds: float
    holdout: str
    orders_evidence: Any = None
    notes: list[str] = field(default_factory=list)
    search: dict[str, Any] = field(default_factory=dict)

    @property
    def model(self) -> Any:
        return self.fit.model

    @property
    def cut_by_time_limit(self) -> bool:
        return bool(self.search.get("cut_by_time_limit", False))

    @property
    def warnings(self) -> list[str]:
        """The selected model's warnings: its fit's on all estimation data (not that its
        refinement stopped at its evaluation limit: the effort set that limit, and
        ``identify`` has no ``--max-nfev`` to raise it) and its scores' (``simulation``,
        ``one_step``)."""
        from blockid.fitting.dispatch import _evaluation_limit_notes

        budget = _evaluation_limit_notes(self.fit)
        notes = [n for n in self.fit.settings.get("warnings", []) if n not in budget]
        for run in (self.simulation, self.one_step):
            notes += [n for n in (run.warnings if run is not None else []) if n not in notes]
        return notes

    def best_scored(self, n: int) -> list[Score]:
        """The ``n`` scored candidates with the lowest cross-validated RMSE, lowest first
        (ties: by label), and the selected one after them if it is not among them: the
        tables' order. (``ranked`` is the choice's order: the selected candidate first,
        and among near-ties the one with fewer parameters before a lower score.)"""
        ordered = sorted(self.ranked, key=lambda s: (s.rmse, s.candidate.label))[:n]
        if self.selected not in ordered:
            ordered.append(self.selected)
        return ordered

    def _repr_html_(self) -> str:
        """The notebook display: :func:`blockid.reporting.notebook.identify_html`."""
        from blockid.reporting.notebook import identify_html

        return identify_html(self)

    def plot(self, *, which: str | None = None) -> Any:
        """The report's figures of the result (search, output, blocks, linear dynamics):
        a dict of matplotlib figures, or the one ``which`` names; see
        :func:`blockid.reporting.notebook.identify_figures`."""
        from blockid.reporting.notebook import identify_figures

        return identify_figures(self, which)

    def to_dict(self) -> dict[str, Any]:
        sel = self.selected.candidate
        orders = sel.orders()
        selected: dict[str, Any] = {
            "structure": sel.structure,
            "orders": orders,
            "options": _jsonable({k: v for k, v in sel.options.items() if k not in orders}),
            "method": self.fit.method,
            "cv_rmse": self.selected.rmse,
            "fold_rmse": [f.rmse for f in self.selected.folds],
            "scored_on": self.on,
            "simulation": _flat(self.simulation.metrics) if self.simulation else None,
            "one_step": _flat(self.one_step.metrics) if self.one_step else None,
        }
        if self.selected.flags:
            selected["flags"] = list(self.selected.flags)
        if self.one_step_error:
            selected["one_step_error"] = self.one_step_error
        if self.warnings:
            selected["warnings"] = self.warnings
        return {
            "selected": selected,
            "models": [s.to_dict() for s in self.ranked],
            "search": {
                **self.search,
                "candidates": len(self.ranked) + len(self.rejected),
                "rejected": [s.to_dict() for s in self.rejected],
                "holdout": self.holdout,
                "seconds": round(self.seconds, 3),
                "notes": self.notes,
            },
        }


def _flat(metrics: dict[str, dict[str, float]]) -> dict[str, Any]:
    """``{"rmse": {"y": v}}`` -> ``{"rmse": v}`` for one output, unchanged for several."""
    if all(len(v) == 1 for v in metrics.values()):
        return {k: next(iter(v.values())) for k, v in metrics.items()}
    return metrics
