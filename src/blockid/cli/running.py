"""``blockid simulate`` and ``predict``: run a saved model on data and score it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import typer

from blockid.cli._common import (
    cli_errors,
    metrics_table,
    print_json,
    refuse_figures,
    refuse_to_overwrite,
    stderr,
    stdout,
)
from blockid.cli._data import check_arguments, data_label, load_model_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Force,
    Json,
    ModelPath,
    Quiet,
    Reading,
    SampleRange,
    reads_data,
    shared,
)

__all__ = ["predict", "simulate"]

OutTable = Annotated[
    Path | None,
    shared("out", "Write data and model output (.csv/.parquet)."),
]

PlotDir = Annotated[
    Path | None,
    shared("plot", "Write a figure (measured vs model output and the error, whole record) here."),
]

InitialSamples = Annotated[
    int | None,
    typer.Option(
        "--initial-samples",
        metavar="N",
        help="simulate: start each experiment from its first N measured outputs (more "
        "than the model's max_lag: a block model estimates its initial state from them) "
        "and score from sample max(N, max_lag) on. Default: max_lag.",
        show_default=False,
    ),
]

_LABELS = {"simulation": "free-run simulation", "one-step": "one-step-ahead prediction"}


def _model_command(mode: str, doc: str) -> Callable[..., None]:
    """``simulate`` / ``predict``: the same options, another mode of evaluation."""

    @reads_data
    @cli_errors
    def command(
        model_path: ModelPath,
        data_paths: DataPaths,
        rng: SampleRange = None,
        out: OutTable = None,
        plot: PlotDir = None,
        reading: Reading = DEFAULT_READING,
        band: Annotated[
            float | None,
            typer.Option(
                "--band",
                metavar="LEVEL",
                help="simulate: confidence band (e.g. 0.95) of the output, from the "
                "parameter covariance in the model file (fit --standard-errors).",
                show_default=False,
            ),
        ] = None,
        initial_samples: InitialSamples = None,
        horizon: Annotated[
            int | None,
            typer.Option(
                "--horizon",
                metavar="K",
                min=1,
                help="predict: the prediction K samples ahead, from the outputs measured "
                "up to K samples back (1: one step, the default; the record's length or "
                "more: the free run).",
                show_default=False,
            ),
        ] = None,
        force: Force = False,
        json_out: Json = False,
        quiet: Quiet = False,
    ) -> None:
        from blockid.errors import ParameterError

        if horizon is not None and mode != "one-step":
            raise ParameterError(
                "--horizon applies to predict only (simulate is the free run: every "
                "horizon at once); use blockid predict --horizon K",
                parameter="horizon",
            )

        if band is not None and mode != "simulation":
            raise ParameterError(
                "--band applies to simulate only (a band of the free-run output)",
                parameter="band",
            )
        if band is not None and not 0.0 < band < 1.0:
            raise ParameterError(
                f"--band must be a confidence level between 0 and 1 (e.g. 0.95), got {band:g}",
                parameter="band",
            )
        refuse_to_overwrite(out, force)
        check_arguments(data_paths, ranges={"--range": rng}, model=model_path, table=out)
        from blockid.data import write_table
        from blockid.evaluation import evaluate
        from blockid.plotting.runs import RUN_FIGURES

        refuse_figures(plot, [RUN_FIGURES[mode]], force)
        model, data = load_model_data(model_path, data_paths, reading, rng)
        if band is not None and initial_samples is not None and initial_samples > model.max_lag:
            raise ParameterError(
                f"--band is the band of the simulation started from the first {model.max_lag} "
                f"measured outputs (max_lag); --initial-samples {initial_samples} starts from an "
                "estimated state instead. Drop one of them",
                parameter="band",
            )
        if horizon is not None and horizon > 1:
            from blockid.evaluation.horizon import predict as predict_ahead

            result = predict_ahead(model, data, horizon)
        else:
            result = evaluate(model, data, mode, initial_samples=initial_samples)
        where = data_label(data_paths, rng)
        if result.diverged is not None:
            from blockid.errors import SimulationError

            raise SimulationError(
                f"the model's {_LABELS[mode]} diverges on {where}: {result.diverged}; its "
                "metrics would mean nothing, so none are printed and nothing is written: "
                "refit the model (the fits keep every pole inside the unit circle) or "
                "check the model file"
            )
        columns = {}
        if band is not None:
            from blockid.evaluation.uncertainty import band_columns, load_covariance

            columns = band_columns(model, load_covariance(model_path), data, band)
        if out is not None:
            frame = result.to_frame()
            for key, values in columns.items():
                frame[key] = values
            write_table(frame, out, overwrite=force)
        figure = None
        if plot is not None:
            from blockid.plotting.runs import run_figure

            figure = run_figure(result, plot, data_label=where, overwrite=force)
        for note in result.warnings:  # with --json too: stderr (and in the document)
            stderr.print(f"warning: {note}", markup=False)
        if json_out:
            paths = [str(p) for p in data_paths]
            doc = {"model": str(model_path), "data": paths, "range": rng, **result.to_dict()}
            if band is not None:
                width = {
                    n: float((columns[f"{n}_upper"] - columns[f"{n}_lower"]).mean())
                    for n in model.outputs
                }
                doc["band"] = {"level": band, "mean_width": width}
            print_json(doc)
            return
        if quiet:  # the files written and the warnings above say what happened
            return
        title = f"{_LABELS[mode]} on {where}"
        if horizon is not None and horizon > 1:
            title = f"{horizon}-step-ahead prediction on {where}"
        if initial_samples is not None:
            title += f", started from {initial_samples} measured outputs"
        stdout.print(metrics_table(title, [(model.structure, result.metrics)]))
        if out is not None:
            stdout.print(f"model output written to {out}")
        if figure is not None:
            stdout.print(f"figure written to {figure}")

    command.__doc__ = doc
    return command


simulate = _model_command(
    "simulation",
    "Free-run simulation of a model on the inputs in DATA (outputs used for metrics).",
)
predict = _model_command(
    "one-step",
    "One-step-ahead prediction of a model on DATA (measured past outputs fed in).",
)
