"""The report's section on the best linear approximation of the estimation data: how
much of the output a linear model can explain, and where in frequency the nonlinear
distortion stands above the noise (:func:`~blockid.evaluation.bla.best_linear_approximation`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from blockid.data.dataset import Dataset
from blockid.errors import BlockidError
from blockid.plotting.html import encode_png
from blockid.reporting.entries import Entry
from blockid.reporting.html import figure, paragraph, section, table

__all__ = ["bla_section"]


def bla_section(estimation: Dataset, where: str, entries: Sequence[Entry] = ()) -> str:
    """The measured BLA of ``estimation`` (described by ``where``, e.g. "estimation
    range 0:1100"): its verdict, notes, band table and figure, and each model of
    ``entries`` checked against it (:func:`_models_part`); with several inputs or
    outputs, or data it cannot be measured on, one paragraph saying why."""
    parts = [
        paragraph(
            "The best linear approximation (BLA) of the estimation data, measured without "
            "a model: on periodic data (several periods or realisations of a multisine) "
            "the noise and the nonlinear distortion are told apart, per band; on other "
            "data Welch's estimate with its coherence. It answers whether a nonlinear "
            "model is worth its parameters, and where in frequency (docs/bla.md)."
        )
    ]
    if estimation.n_inputs != 1 or estimation.n_outputs != 1:
        parts.append(
            paragraph(
                f"Not measured: the data have {estimation.n_inputs} input(s) and "
                f"{estimation.n_outputs} output(s); the BLA here is measured from one "
                "input to one output (blockid bla -u U -y Y for a pair)."
            )
        )
        return section("bla", "Best linear approximation", parts)
    from blockid.evaluation.bla import best_linear_approximation

    try:
        bla = best_linear_approximation(estimation, data_label=where)
    except BlockidError as periodic:
        try:  # e.g. a periodic input cut at a range that is no whole number of periods
            bla = best_linear_approximation(estimation, method="welch", data_label=where)
        except BlockidError as exc:
            parts.append(paragraph(f"Not measured on these data: {exc}"))
            return section("bla", "Best linear approximation", parts)
        parts.append(paragraph(f"Welch's estimate, as the periodic one failed: {periodic}"))
    entry = bla.report_entry()
    parts.append(paragraph(entry["title"]))
    parts.append(paragraph(f"Verdict: {entry['verdict']}", "note"))
    parts += [paragraph(note) for note in entry["notes"]]
    parts.append(table(entry["columns"], entry["rows"]))
    import matplotlib.pyplot as plt

    fig = bla.plot()
    try:
        png = encode_png(fig)
    finally:
        plt.close(fig)
    parts.append(
        figure(
            png,
            "best linear approximation, noise and distortion levels",
            f"The BLA's magnitude, its noise level and (periodic data) its total and "
            f"distortion levels, measured on the {where}; no model involved.",
        )
    )
    parts += _models_part(bla, entries, where)
    return section("bla", "Best linear approximation", parts)


def _models_part(bla: Any, entries: Sequence[Entry], where: str) -> list[str]:
    """Each model's linear frequency response against the BLA and its bound: a table
    (the gain a block model's response is scaled by, the lines within the bound, the
    mean squared distance over the BLA's variance) and a figure
    (:mod:`blockid.plotting.bla_models`); the models not compared, and why."""
    from blockid.plotting.bla_models import model_response, plot_bla_models

    found = [model_response(e.label, e.model, bla) for e in entries if e.model is not None]
    responses = [r for r in found if not isinstance(r, str)]
    skipped = [r for r in found if isinstance(r, str)]
    if not responses:
        return (
            [paragraph("Models not compared with the BLA: " + "; ".join(skipped))]
            if skipped
            else []
        )
    level = f"{bla.confidence:.0%}"
    rows = [
        [r.label, "-" if r.gain is None else f"{r.gain:.4g}",
         "-" if r.within is None else f"{100 * r.within:.0f} %",
         "-" if r.ratio is None else f"{r.ratio:.3g}"]
        for r in responses
    ]  # fmt: skip
    parts = [
        paragraph(
            "Each model's linear frequency response against the BLA: a linear model's as "
            "it is, a block-oriented model's linear blocks (their product) scaled by the "
            "real gain that fits them best to the BLA, since a static block's gain cannot "
            "be told from the linear block's. A model whose response leaves the BLA's "
            f"{level} bound at many lines, or whose mean squared distance is many times "
            "the BLA's variance (about 1 when they agree), has linear dynamics the "
            "measurement does not support."
        ),
        table(
            [
                "model",
                "gain (scaled)",
                f"lines within the {level} bound",
                "mean |G - model|² / var G",
            ],
            rows,
        ),  # fmt: skip
    ]
    if skipped:
        parts.append(paragraph("Not compared: " + "; ".join(skipped)))
    parts.append(
        figure(
            encode_png(plot_bla_models(bla, responses)),  # closes it
            "models' linear responses against the BLA",
            f"Top: the BLA measured on the {where} (dots) with its {level} bound (shaded) "
            "and each model's linear response (lines; a block model's scaled by the gain "
            "in its label). Bottom: each model's distance from the BLA, |G - model|, "
            "against the bound (grey line): below it, the model agrees with the "
            "measurement at that line.",
        )
    )
    return parts
