"""The report's section on residual tests: per model, is its residual on the data it was
scored on white, and independent of the inputs
(:func:`~blockid.evaluation.residuals.residual_analysis`, ``blockid residuals``)?"""

from __future__ import annotations

from typing import Any

from blockid.evaluation.residuals import residual_check
from blockid.plotting.html import encode_png
from blockid.reporting.entries import Entry, heading
from blockid.reporting.html import figure, paragraph, section, table

__all__ = ["residual_rows", "residuals_section"]

_MODE = {"one-step": "one-step prediction", "simulation": "free-run simulation"}


def residual_rows(analysis: Any) -> list[list[str]]:
    """The tests as table rows: test, statistic, p-value, lags outside, verdict."""
    lags = int(analysis.lags[-1])
    rows = [
        [f"whiteness of {y}", f"{t['statistic']:.4g}", f"{t['p_value']:.3g}",
         f"{t['outside']} of {lags}", "white" if t["white"] else "not white"]
        for y, t in analysis.whiteness.items()
    ]  # fmt: skip
    rows += [
        [f"{u} -> residual of {y} (lags >= 0)", f"{t['statistic']:.4g}", f"{t['p_value']:.3g}",
         f"{t['outside']} of {lags + 1}",
         "independent" if t["independent"] else "not independent"]
        for (u, y), t in analysis.independence.items()
    ]  # fmt: skip
    return rows


def residuals_section(entries: list[Entry]) -> str:
    """Per model: the one-line verdict, the table of tests and the figure of the
    residual's autocorrelation and cross-correlation with each input, with their bounds,
    on the data the model was scored on. A model's analysis made by ``compare``
    (``Entry.residuals``) is reused; the others are made here."""
    parts = [
        paragraph(
            "What each model leaves on the data it was scored on, tested as MATLAB's resid "
            "does (Ljung 1999, sec. 16.6): the residual of its one-step prediction (of its "
            "free run for a model without a one-step predictor) should be independent of "
            "past inputs, or the model misses input dynamics or a nonlinearity; a model "
            "fitted with a noise model (least-squares ARX, a state space with its "
            "predictor gain) should also leave it white. A model fitted by simulation "
            "error has no noise model, and whiteness is not asked of it. Bounds and tests "
            "at 99 %; docs/cli.md#residuals."
        )
    ]
    from blockid.plotting.residuals import plot_residuals

    for e in entries:
        if e.simulation is None or e.model is None:
            continue
        analysis, why = getattr(e, "residuals", None), None
        if analysis is None:
            analysis, why = residual_check(e.model, e.simulation.data)
        parts.append(heading(e))
        if analysis is None:
            parts.append(paragraph(f"Not tested: {why}"))
            continue
        parts.append(paragraph(f"Verdict: {e.label} {analysis.verdict()}.", "note"))
        parts.append(
            table(
                ["test", "statistic", "p-value", "lags outside", "verdict"], residual_rows(analysis)
            )
        )
        where = f"{e.on} data"
        parts.append(
            figure(
                encode_png(plot_residuals(analysis, data_label=where)),  # closes it
                f"{e.label}: residual correlations",
                f"{e.label}: the residual of the {_MODE[analysis.mode]} on the {where} "
                f"({analysis.n_samples} samples): its autocorrelation (left) and its "
                "cross-correlation with each input at t and the residual at t + τ (right; "
                "τ < 0 would mean feedback in the data), the 99 % bounds shaded.",
            )
        )
    if len(parts) == 1:
        parts.append(paragraph("No model was identified."))
    return section("residuals", "Residual tests", parts)
