"""``blockid residuals``: is a model's residual white, and independent of the input?"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from blockid.cli._common import cli_errors, flagged, print_json, refuse_figures, stdout
from blockid.cli._data import check_arguments, data_label, load_model_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Force,
    Json,
    ModelPath,
    Reading,
    SampleRange,
    reads_data,
    shared,
)

__all__ = ["residuals"]


@reads_data
@cli_errors
def residuals(
    model_path: ModelPath,
    data_paths: DataPaths,
    rng: SampleRange = None,
    mode: Annotated[
        str,
        typer.Option(
            metavar="one-step|simulation",
            help="The residual of the one-step prediction (default) or of the free run.",
        ),
    ] = "one-step",
    lags: Annotated[int, typer.Option(metavar="M", min=1, help="Largest lag tested.")] = 25,
    confidence: Annotated[
        float,
        shared("confidence", "Of the bounds and the tests (between 0 and 1)."),
    ] = 0.99,
    plot: Annotated[
        Path | None,
        shared("plot", "Write the figure (autocorrelation, cross-correlation, bounds) here."),
    ] = None,
    reading: Reading = DEFAULT_READING,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Test the residual of MODEL on DATA: its autocorrelation (whiteness, Ljung-Box)
    and its cross-correlation with each input (independence), with confidence bounds.
    Use data the model was not fitted on."""
    from blockid.errors import ParameterError

    if mode not in ("one-step", "simulation"):
        raise ParameterError(f"--mode {mode!r}: choose one-step or simulation", parameter="mode")
    check_arguments(data_paths, ranges={"--range": rng}, model=model_path)
    from blockid.evaluation.residuals import residual_analysis
    from blockid.plotting.residuals import RESIDUAL_FIGURE

    refuse_figures(plot, [RESIDUAL_FIGURE], force)
    model, data = load_model_data(model_path, data_paths, reading, rng)
    with flagged({"max_lag": "--lags", "confidence": "--confidence"}.get):
        analysis = residual_analysis(model, data, mode, max_lag=lags, confidence=confidence)
    where = data_label(data_paths, rng)
    figure = None
    if plot is not None:
        from blockid.plotting.residuals import residual_figure

        figure = residual_figure(analysis, plot, data_label=where, overwrite=force)
    if json_out:
        print_json({"model": str(model_path), "data": [str(p) for p in data_paths],
                    "range": rng, **analysis.to_dict()})  # fmt: skip
        return
    from rich.table import Table

    what = "free-run simulation" if mode == "simulation" else "one-step prediction"
    title = (f"residual of the {what} on {where}: {analysis.n_samples} samples, lags up "
             f"to {lags}, {confidence:.0%} bounds")  # fmt: skip
    table = Table(title=title, title_justify="left")
    for col in ("test", "statistic", "p-value", "lags outside", "verdict"):
        table.add_column(col)
    for y, t in analysis.whiteness.items():
        verdict = "white" if t["white"] else "NOT white"
        table.add_row(f"whiteness of {y}", f"{t['statistic']:.4g}", f"{t['p_value']:.3g}",
                      f"{t['outside']} of {lags}", verdict)  # fmt: skip
    for (u, y), t in analysis.independence.items():
        table.add_row(
            f"{u} -> residual of {y} (lags >= 0)", f"{t['statistic']:.4g}",
            f"{t['p_value']:.3g}", f"{t['outside']} of {lags + 1}",
            "independent" if t["independent"] else "NOT independent",
        )  # fmt: skip
    stdout.print(table)
    stdout.print(f"verdict: the model {analysis.verdict()}", soft_wrap=True, markup=False)
    feedback = [f"{u} -> {y} (p = {t['feedback_p_value']:.2g})"
                for (u, y), t in analysis.independence.items() if t["feedback"]]  # fmt: skip
    if feedback:
        stdout.print(
            "note: the residual correlates with later inputs (negative lags, the input "
            f"prewhitened) for {', '.join(feedback)}: feedback from the output to the "
            "input in the data (a closed loop), not a fault of the model; the independence "
            "test assumes open-loop data, so its verdict is not to be trusted here"
        )
    if analysis.noise_model is False and not all(t["white"] for t in analysis.whiteness.values()):
        stdout.print(
            "note: this model was fitted by simulation error, without a noise model: it is "
            "not made to leave a white one-step residual (the plant's noise is coloured), "
            "so whiteness is not expected of it; independence is the test that matters"
        )
    if figure is not None:
        stdout.print(f"figure written to {figure}")
