"""What an ``identify`` result shows in a notebook, and the figures its ``.plot()`` returns.

``IdentifyResult._repr_html_`` hands off to :func:`identify_html`: the chosen model and
how it was chosen, its scores on the validation data, the best ARX model of the search
beside it (its cross-validation score: the result holds no estimation data to refit it,
which the report does), the best candidates, the rejected ones with their reasons, and
the chosen fit's own summary (:func:`blockid.plotting.notebook.fit_html`: parameters with
standard errors, linear dynamics, the static curves). ``IdentifyResult.plot`` hands off
to :func:`identify_figures`: the report's figures of the result.
"""

from __future__ import annotations

from html import escape
from typing import Any

from blockid.plotting.html import table
from blockid.plotting.notebook import FIGURES, STYLE, fit_html
from blockid.reporting.entries import predicts_by_free_run
from blockid.reporting.search import best_linear

__all__ = ["IDENTIFY_FIGURES", "identify_figures", "identify_html"]

#: The figures :func:`identify_figures` can draw.
IDENTIFY_FIGURES = ("search", *FIGURES)

#: Candidates listed in the summary.
_TOP = 5


def _scores(output: Any) -> str:
    if output is None:
        return "not scored"
    metrics = output.metrics
    return "; ".join(
        f"{o}: fit {metrics['fit_percent'][o]:.1f} %, RMSE {metrics['rmse'][o]:.4g}"
        for o in output.data.outputs
    )


def identify_html(result: Any) -> str:
    """A compact HTML summary of an :class:`~blockid.workflows.identify.IdentifyResult`."""
    sel = result.selected
    search = getattr(result, "search", {}) or {}
    p = "<p style='margin:.25em 0'>{}</p>".format
    parts = [
        p(
            f"<b>identify()</b> chose <b>{escape(sel.candidate.label)}</b> (stage "
            f"{escape(sel.stage)}, {sel.n_parameters} parameters, cross-validated free-run "
            f"RMSE {sel.rmse:.4g}, fit {sel.fit_percent:.1f} %) among {len(result.ranked)} "
            f"scored candidates; {len(result.rejected)} rejected; {result.seconds:.1f} s, "
            f"effort {escape(str(search.get('effort', '?')))}."
        ),
        p(
            escape(
                f"Free-run simulation on the {result.on} data: {_scores(result.simulation)}; "
                f"one-step prediction: "
                + (
                    "the same as the free run, sample for sample (the model has no one-step "
                    "predictor but its free run)"
                    if predicts_by_free_run(result.simulation, result.one_step)
                    else _scores(result.one_step)
                    if result.one_step is not None
                    else f"none ({result.one_step_error})"
                )
                + "."
            )
        ),
    ]
    rank, best = best_linear(result.ranked)
    if best is None:
        parts.append(p("Linear baseline: the search scored no ARX model."))
    elif best.candidate == sel.candidate:
        parts.append(p("Linear baseline: the chosen model is itself the best ARX model."))
    else:
        parts.append(
            p(
                escape(
                    f"Linear baseline: the best ARX model, {best.candidate.label}, ranked "
                    f"{rank + 1}: cross-validated RMSE {best.rmse:.4g} (fit {best.fit_percent:.1f} "
                    f"%) against {sel.rmse:.4g} ({sel.fit_percent:.1f} %). The report refits it "
                    "and scores it on the validation data."
                )
            )
        )
    if result.cut_by_time_limit:
        parts.append(p("The time limit cut the search: another run may choose differently."))
    for flag in sel.flags:
        parts.append(p(escape(f"Flag: {flag}")))
    rows = [
        [s.candidate.label, s.stage, s.n_parameters, s.rmse, s.fit_percent]
        for s in result.best_scored(_TOP)
    ]
    header = ["candidate (lowest CV RMSE first)", "stage", "parameters", "CV RMSE", "CV fit %"]
    parts.append(
        f"<details><summary>best {len(rows)} candidates</summary>{table(header, rows)}</details>"
    )
    if result.rejected:
        rejected = [[s.candidate.label, s.stage, s.reason] for s in result.rejected]
        parts.append(
            f"<details><summary>{len(rejected)} rejected candidates</summary>"
            f"{table(['candidate', 'stage', 'reason'], rejected)}</details>"
        )
    parts.append(fit_html(result.fit))
    return f'<div class="blockid-summary" style="{STYLE}">' + "\n".join(parts) + "</div>"


def identify_figures(result: Any, which: str | None = None) -> Any:
    """The report's figures of an ``identify`` result: a dict ``name -> Figure`` or the
    one named by ``which``: ``"search"`` (every scored candidate's cross-validated RMSE
    against its parameters), ``"output"`` (the chosen model's free run on the data it was
    scored on, with a zoom on long records), ``"blocks"``, ``"linear"`` and
    ``"parameters"`` (:func:`blockid.plotting.notebook.model_figures`)."""
    from blockid.errors import ParameterError
    from blockid.plotting.notebook import model_figures
    from blockid.plotting.report_figures import search_figure, validation_figure
    from blockid.plotting.uncertainty import fit_draws, output_bands

    if which is not None and which not in IDENTIFY_FIGURES:
        raise ParameterError(
            f"which={which!r}: choose one of {', '.join(IDENTIFY_FIGURES)}", parameter="which"
        )
    out: dict[str, Any] = {}
    if which in (None, "search") and len(result.ranked) > 1:
        points = [(s.candidate.structure, s.n_parameters, s.rmse) for s in result.ranked]
        chosen = next((k for k, s in enumerate(result.ranked) if s is result.selected), None)
        out["search"] = search_figure(points, chosen, best_linear(result.ranked)[0])
    if which in (None, "output") and result.simulation is not None:
        bands, _ = output_bands(result.fit, result.simulation, fit_draws(result.fit))
        out["output"] = validation_figure(result.simulation, 0, bands, f"{result.on} data")
    if which is None:
        return {**out, **model_figures(result.fit.model, fit=result.fit)}
    if which in ("search", "output"):
        if which not in out:
            raise ParameterError(f"no {which!r} figure for this result", parameter="which")
        return out[which]
    return model_figures(result.fit.model, fit=result.fit, which=which)
