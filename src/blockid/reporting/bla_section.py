"""The report's section on the best linear approximation of the estimation data: how
much of the output a linear model can explain, and where in frequency the nonlinear
distortion stands above the noise (:func:`~blockid.evaluation.bla.best_linear_approximation`)."""

from __future__ import annotations

from blockid.data.dataset import Dataset
from blockid.errors import BlockidError
from blockid.plotting.html import encode_png
from blockid.reporting.html import figure, paragraph, section, table

__all__ = ["bla_section"]


def bla_section(estimation: Dataset, where: str) -> str:
    """The measured BLA of ``estimation`` (described by ``where``, e.g. "estimation
    range 0:1100"): its verdict, notes, band table and figure; with several inputs or
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
    return section("bla", "Best linear approximation", parts)
