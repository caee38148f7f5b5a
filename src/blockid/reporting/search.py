"""The report's part about an ``identify`` run: its search, and a linear baseline.

The baseline is the best ARX model the search scored, refitted with its own options on
the same estimation data as the chosen model and scored on the same validation data: the
answer to "how much does the nonlinear model buy over a linear one?", in the comparison
table beside the chosen model.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from blockid.data.dataset import Dataset
from blockid.plotting import report_figures as figures
from blockid.plotting.html import encode_png
from blockid.reporting.entries import Entry
from blockid.reporting.html import figure, paragraph, section, table

__all__ = ["LinearBaseline", "baseline_entry", "linear_baseline", "search_section"]

#: Candidates listed in the search table (the rest are counted).
SHOWN = 20


@dataclass
class LinearBaseline:
    """The best ARX model of an ``identify`` search, refitted and scored as the chosen
    one was. ``score``: its cross-validation score in the search (None: the search
    scored none); ``fit``, ``simulation``, ``one_step``: its refit on the estimation data
    and its scores on the data the chosen model was scored on (None, with ``reason``,
    when there is no separate baseline or its refit failed)."""

    score: Any = None
    fit: Any = None
    simulation: Any = None
    one_step: Any = None
    one_step_error: str | None = None
    reason: str = ""


def best_linear(ranked: Any) -> tuple[int, Any] | tuple[None, None]:
    """Rank and score of the best ARX candidate among ``ranked`` (best first)."""
    from blockid.workflows.search_space import LINEAR

    for k, score in enumerate(ranked):
        if score.candidate.structure == LINEAR:
            return k, score
    return None, None


def linear_baseline(identify: Any, estimation: Dataset) -> LinearBaseline:
    """The best ARX candidate of ``identify.ranked`` refitted on ``estimation`` with its
    own options (:func:`blockid.fitting.fit_model`) and scored free-run and one step
    ahead (:func:`blockid.evaluation.validate.score_model`) on the data ``identify``
    scored its choice on; with standard errors when the chosen fit carries them."""
    from blockid.errors import BlockidError
    from blockid.evaluation.validate import score_model
    from blockid.fitting.dispatch import fit_model

    _, best = best_linear(identify.ranked)
    if best is None:
        return LinearBaseline(reason="the search scored no ARX model")
    if best.candidate == identify.selected.candidate:
        return LinearBaseline(best, reason="the chosen model is itself the best ARX model")
    options = dict(best.candidate.options)
    if "covariance" in (getattr(identify.fit, "settings", None) or {}):
        options["standard_errors"] = True
    target = identify.simulation.data if identify.simulation is not None else estimation
    try:
        with np.errstate(all="ignore"):
            fit = fit_model(estimation, best.candidate.structure, **options)
            simulation, one_step, one_step_error = score_model(fit.model, target)
    except BlockidError as exc:
        return LinearBaseline(best, reason=f"its refit on the estimation data failed: {exc}")
    return LinearBaseline(best, fit, simulation, one_step, one_step_error)


def baseline_entry(baseline: LinearBaseline, on: str) -> Entry | None:
    """The baseline as a model of the report (None without a refitted baseline)."""
    if baseline.fit is None:
        return None
    return Entry(
        f"linear baseline: {baseline.score.candidate.label}",
        baseline.fit.method,
        baseline.fit,
        baseline.simulation,
        baseline.one_step,
        None,
        baseline.one_step_error,
        on,
        row="baseline",
    )


def _fit_text(output: Any) -> str:
    if output is None:
        return "not scored"
    return "; ".join(
        f"fit {output.metrics['fit_percent'][o]:.1f} % (RMSE {output.metrics['rmse'][o]:.4g})"
        + (f" on {o}" if len(output.data.outputs) > 1 else "")
        for o in output.data.outputs
    )


def _baseline_text(identify: Any, baseline: LinearBaseline) -> str:
    rank, best = best_linear(identify.ranked)
    if best is None:
        return (
            "Linear baseline: none, the search scored no ARX model (an ARX model is the "
            "first stage of a search over every structure)."
        )
    sel = identify.selected
    cv = (
        f"the best ARX model of the search, {best.candidate.label}, ranked {rank + 1} of "
        f"{len(identify.ranked)} with a cross-validated RMSE of {best.rmse:.4g} (fit "
        f"{best.fit_percent:.1f} %), against {sel.rmse:.4g} ({sel.fit_percent:.1f} %) for "
        "the chosen model"
    )
    if baseline.fit is None:
        return f"Linear baseline: {cv}. Not refitted: {baseline.reason}."
    where = "validation" if identify.on == "validation" else "estimation"
    return (
        f"Linear baseline: {cv}. Refitted on the same estimation data and run free on the "
        f"same {where} data, it scores {_fit_text(baseline.simulation)}; the chosen model "
        f"{_fit_text(identify.simulation)} (the 'linear baseline' rows of the comparison)."
    )


def search_section(identify: Any, baseline: LinearBaseline) -> str:
    """The search of ``identify``: how it chose, the linear baseline, the best candidates,
    a figure of all scored candidates, and the rejected ones with their full reasons."""
    sel = identify.selected
    search = getattr(identify, "search", {}) or {}
    cut = (
        " The time limit cut the search: candidates not fitted by then were left out, "
        "and another run may choose differently."
        if search.get("cut_by_time_limit")
        else ""
    )
    parts = [
        paragraph(
            f"identify() chose {sel.candidate.label} by its cross-validated free-run RMSE "
            f"on the estimation data ({identify.holdout}; folds combined by their "
            f"{search.get('rule', 'geometric-mean').replace('-', ' ')}); "
            f"among near-ties the model with the fewest parameters wins. "
            f"{len(identify.ranked)} candidates scored, {len(identify.rejected)} rejected, "
            f"in {identify.seconds:.1f} s (effort {search.get('effort', '?')}). The chosen "
            "model was refitted on all estimation data; validation data were not used to "
            f"choose.{cut}"
        ),
        paragraph(_baseline_text(identify, baseline)),
    ]
    for flag in sel.flags:
        parts.append(paragraph(f"Flag on the chosen model: {flag}", "note"))
    rank, best = best_linear(identify.ranked)
    shown = identify.best_scored(SHOWN)
    if best is not None and best not in shown:
        shown.append(best)  # the baseline's row, below the best ones
    rows = [
        [s.candidate.label, s.stage, s.n_parameters, s.rmse, s.fit_percent, s.seconds]
        for s in shown
    ]
    classes = ["best" if s is sel else "baseline" if s is best else None for s in shown]
    header = ["candidate (lowest CV RMSE first)", "stage", "parameters", "CV RMSE", "CV fit %",
              "seconds"]  # fmt: skip
    parts.append(table(header, rows, classes))
    if len(identify.ranked) > SHOWN:
        more = len(identify.ranked) - len(shown)
        parts.append(paragraph(f"... and {more} more candidates (in the figure below)."))
    if len(identify.ranked) > 1:
        points = [(s.candidate.structure, s.n_parameters, s.rmse) for s in identify.ranked]
        chosen = next((k for k, s in enumerate(identify.ranked) if s is sel), None)
        fig = figures.search_figure(points, chosen, rank)
        parts.append(
            figure(
                encode_png(fig),
                "every scored candidate of the search",
                f"Every scored candidate ({len(points)}): its cross-validated free-run RMSE "
                "on the estimation data against its number of parameters, coloured by "
                "structure; the chosen model starred"
                + (", the linear baseline boxed." if rank is not None else "."),
            )
        )
    if identify.rejected:
        parts.append("<h3>Rejected candidates</h3>")
        parts.append(
            table(
                ["candidate", "stage", "reason"],
                [[s.candidate.label, s.stage, s.reason] for s in identify.rejected],
                ["failed"] * len(identify.rejected),
            )
        )
    for note in identify.notes:
        parts.append(paragraph(note, "note"))
    return section("search", "Search of identify()", parts)
