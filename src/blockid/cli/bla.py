"""``blockid bla``: the best linear approximation of a plant, measured, with its noise
and nonlinear distortion levels per band
(:func:`blockid.evaluation.bla.best_linear_approximation`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import (
    busy,
    cli_errors,
    flagged,
    print_json,
    refuse_figures,
    refuse_model_name,
    refuse_to_overwrite,
    stdout,
)
from blockid.cli._data import check_arguments, data_label, load_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Force,
    Inputs,
    Json,
    Outputs,
    Quiet,
    Reading,
    SampleRange,
    reads_data,
    shared,
)
from blockid.cli._tables import print_summary
from blockid.errors import BlockidError, ParameterError

__all__ = ["bla"]

#: Library parameter -> this command's flag, for the one-line errors.
FLAGS = {
    "period": "--period",
    "periods": "--periods",
    "transient_periods": "--transient-periods",
    "segment": "--segment",
    "bands": "--bands",
    "confidence": "--confidence",
    "method": "--method",
    "input": "--input",
    "output": "--output",
}
METHODS = ("auto", "robust", "welch")


def _option(flag: str, metavar: str, help: str, **kwargs: Any) -> Any:
    return typer.Option(flag, metavar=metavar, help=help, **kwargs)


@reads_data
@cli_errors
def bla(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    period: Annotated[
        int | None,
        _option(
            "--period",
            "N",
            "Samples in one period [default: found from the input].",
            show_default=False,
        ),
    ] = None,
    periods: Annotated[
        int | None,
        shared("periods", "Or: the periods each realisation holds.", show_default=False),
    ] = None,
    transient_periods: Annotated[
        int | None,
        _option(
            "--transient-periods",
            "K",
            "Periods dropped from the start of each realisation (the plant's transient) "
            "[default: the first, when it differs clearly more from the others than they "
            "differ among themselves].",
            min=0,
            show_default=False,
        ),
    ] = None,
    method: Annotated[
        str,
        shared(
            "method",
            "robust: periods and realisations "
            "(Pintelon-Schoukens); welch: any data (noise and distortion not told "
            "apart); auto: robust when the input repeats.",
            metavar="auto|robust|welch",
        ),
    ] = "auto",
    segment: Annotated[
        int | None,
        _option(
            "--segment",
            "N",
            "welch: samples of a segment (the resolution) [default: "
            "the longest power of two that leaves 16 segments].",
            show_default=False,
        ),
    ] = None,
    bands: Annotated[
        str,
        _option(
            "--bands",
            "N|LOW:HIGH,..",
            "Bands of the summary: a number (equal numbers of lines) or edges in Hz.",
        ),
    ] = "4",
    confidence: Annotated[
        float, shared("confidence", "Of the bounds and the tests (between 0 and 1).")
    ] = 0.99,
    fit: Annotated[
        str | None,
        _option(
            "--fit",
            "NA,NB[,NK]",
            "Also fit a transfer function z^-NK B/A (NA poles, NB numerator coefficients, "
            "NK delay, default 0) to the BLA, weighted by its variance; printed, and in "
            "--json / -o.",
            show_default=False,
        ),
    ] = None,
    rng: SampleRange = None,
    plot: Annotated[
        Path | None,
        shared("plot", "Write the figure (BLA, noise and distortion levels) to DIR/bla.png."),
    ] = None,
    out: Annotated[
        Path | None, shared("out", "Write the results (the --json document) to this file.")
    ] = None,
    reading: Reading = DEFAULT_READING,
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Measure the best linear approximation of DATA from -u to -y: its frequency
    response, the noise level and the nonlinear distortion level per band, and whether a
    nonlinear model is worth trying. Periodic data (several periods and realisations of
    a multisine, one realisation per experiment) separate noise from distortion; other
    data get Welch's estimate with its coherence. Give each realisation as its own
    experiment (--experiment-column, e.g. the 'realisation' column of 'blockid design')."""
    if len(inputs) != 1 or len(outputs) != 1:
        raise ParameterError(
            f"the BLA is measured from one input to one output; got {len(inputs)} input(s) and "
            f"{len(outputs)} output(s): run the command once per pair"
        )
    input, output = inputs[0], outputs[0]
    if method not in METHODS:
        raise ParameterError(f"--method {method!r}: choose {', '.join(METHODS)}")
    orders = None if fit is None else _orders(fit)
    check_arguments(data_paths, ranges={"--range": rng})
    refuse_model_name(out, "the results are")
    refuse_to_overwrite(out, force)
    from blockid.evaluation.bla import best_linear_approximation
    from blockid.evaluation.bla_bands import parse_bands
    from blockid.plotting.bla import BLA_FIGURE

    refuse_figures(plot, [BLA_FIGURE], force)
    where = data_label(data_paths, rng)
    with busy("measuring the best linear approximation", quiet or json_out):
        data = load_data(data_paths, [input], [output], reading,
                         rng, "--range")  # fmt: skip
        options = {"method": method, "period": period, "periods": periods,
                   "transient_periods": transient_periods, "segment": segment,
                   "confidence": confidence}  # fmt: skip
        with flagged(FLAGS.get):
            result = best_linear_approximation(
                data, bands=parse_bands(bands), data_label=where, **options
            )
    figure = None
    if plot is not None:
        from blockid.plotting.bla import bla_figure

        figure = bla_figure(result, plot, overwrite=force)
    doc = result.to_dict()
    fitted = None
    if orders is not None:
        from blockid.fitting.frequency import fit_bla

        try:
            fitted = fit_bla(result, *orders)
        except BlockidError as exc:  # orders the measured lines cannot carry
            raise type(exc)(f"{exc} (option --fit)") from None
        doc["fit"] = fitted.to_dict()
    if out is not None:
        from blockid.data.io import json_text, write_text_atomic

        write_text_atomic(json_text(doc), out, overwrite=force)
    if json_out:
        print_json({**doc, "figure": None if figure is None else str(figure),
                    "out": None if out is None else str(out)})  # fmt: skip
        return
    print_summary(result.summary_table(), label_column=True)  # the bands, notes, verdict
    if fitted is not None:
        _print_fit(fitted)
    if figure is not None:
        stdout.print(f"figure written to {figure}", markup=False)
    if out is not None:
        stdout.print(f"results written to {out}", markup=False)


def _orders(text: str) -> tuple[int, int, int]:
    """``NA,NB[,NK]`` of ``--fit``."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (2, 3) or not all(p.isdigit() for p in parts):
        raise ParameterError(
            f"--fit {text!r}: give NA,NB or NA,NB,NK (poles, numerator coefficients, "
            "delay; whole numbers), e.g. --fit 2,3",
            parameter="fit",
        )
    na, nb, *rest = (int(p) for p in parts)
    if nb < 1:
        raise ParameterError(f"--fit {text!r}: NB must be 1 or more", parameter="fit")
    return na, nb, rest[0] if rest else 0


def _print_fit(fit: Any) -> None:
    """The fitted coefficients with their standard errors, the cost check, the poles."""
    from rich.table import Table

    table = Table(
        title=f"transfer function z^-{fit.nk} B/A fitted to the BLA ({fit.lines} lines, "
        "weighted by 1/var G)",
        title_justify="left",
    )
    for column in ("coefficient", "value", "standard error"):
        table.add_column(column, justify="left" if column == "coefficient" else "right")
    values = [*fit.a, *fit.b]
    for name, value, se in zip(fit.names(), values, fit.standard_errors, strict=True):
        table.add_row(name, f"{value:.6g}", f"{se:.3g}")
    stdout.print(table)
    ratio = fit.cost_ratio
    reading = (
        "well above 1: the orders miss dynamics the BLA shows"
        if ratio > 2.0
        else "about 1: the orders fit the BLA within its uncertainty"
    )
    stable = "stable" if fit.to_dict()["stable"] else "UNSTABLE"
    largest = max(abs(fit.poles), default=0.0)
    stdout.print(
        f"weighted cost over its expected value for a right model: {ratio:.3g} ({reading}); "
        f"poles {stable}, largest |p| = {largest:.4g}",
        markup=False,
    )
