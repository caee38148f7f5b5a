"""The ``blockid`` command line: thin commands over library functions.

Every command that reports numbers prints them as one JSON document with ``--json``.
Errors in the user's input are printed as one line and the exit status is 2; output
files are written atomically and only after the work succeeded, and an existing file
is replaced only with ``--force``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from blockid.cli._common import (
    cli_errors,
    metrics_table,
    parse_order,
    print_json,
    stdout,
)

__all__ = ["app", "main"]

app = typer.Typer(
    name="blockid",
    help="Identify block-oriented nonlinear models (Hammerstein, Wiener, "
    "Hammerstein-Wiener, backlash, networks) from input/output data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)

DataPaths = Annotated[
    list[Path], typer.Argument(help="Data file(s): .csv, .tsv, .txt, .parquet or .mat.")
]
Inputs = Annotated[
    list[str], typer.Option("--input", "-u", help="Input column; repeat for several inputs.")
]
Outputs = Annotated[
    list[str], typer.Option("--output", "-y", help="Output column; repeat for several outputs.")
]
SamplingTime = Annotated[
    float | None, typer.Option("--ts", help="Sampling time in seconds.", show_default=False)
]
TimeColumn = Annotated[
    str | None,
    typer.Option("--time-column", help="Column of sample times (sampling time inferred)."),
]
ExperimentColumn = Annotated[
    str | None,
    typer.Option("--experiment-column", help="Column labelling the experiment of each row."),
]
Force = Annotated[bool, typer.Option("--force", help="Replace an existing output file.")]
Json = Annotated[bool, typer.Option("--json", help="Print one JSON document on stdout.")]


def _load(paths, inputs, outputs, ts, time_column, experiment_column, rng, what):
    from blockid.data import parse_range, read_data

    data = read_data(
        paths,
        inputs,
        outputs,
        sampling_time=ts,
        time_column=time_column,
        experiment_column=experiment_column,
    )
    if rng:
        start, stop = parse_range(rng, what)
        data = data.select(start, stop, what=what)
    return data


@app.command()
@cli_errors
def fit(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    structure: Annotated[str, typer.Option(help="Model structure: arx.")] = "arx",
    na: Annotated[str, typer.Option(help="Output lags: N or matrix 'N,N;N,N'.")] = "1",
    nb: Annotated[str, typer.Option(help="Input coefficients per channel: N or matrix.")] = "1",
    nk: Annotated[str, typer.Option(help="Input delay in samples: N or matrix.")] = "1",
    method: Annotated[str, typer.Option(help="batch | rls | aw-rls | hierarchical-rls.")] = "batch",
    forgetting: Annotated[
        str, typer.Option(help="Forgetting factor, or schedule such as 0.98:200,1.")
    ] = "1",
    initial_covariance: Annotated[
        float | None, typer.Option(help="P(0) scale of the recursive methods.")
    ] = None,
    eps1: Annotated[float, typer.Option(help="AW-RLS weight eps1 (A8).")] = 1.0,
    eps2: Annotated[float, typer.Option(help="AW-RLS weight eps2 (A8).")] = 0.1,
    center: Annotated[
        bool, typer.Option(help="Fit around the mean operating point (offsets kept).")
    ] = False,
    allow_unstable: Annotated[
        bool, typer.Option(help="Keep a model with poles outside the unit circle.")
    ] = False,
    passes: Annotated[int, typer.Option(help="Passes of a recursive method over the data.")] = 1,
    convergence_check: Annotated[
        bool,
        typer.Option(
            help="Fail when a recursive estimate's one-step MSE exceeds 2x the LS optimum."
        ),
    ] = True,
    estimation: Annotated[
        str | None, typer.Option(help="Estimation samples START:STOP (0-based, stop excluded).")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Model file to write.")] = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    experiment_column: ExperimentColumn = None,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Identify a model from data and save it as a JSON model file."""
    from blockid.errors import ParameterError
    from blockid.fitting import fit_arx
    from blockid.models import model_document, save_model

    if out is None and not json_out:
        raise ParameterError("nothing to do: give -o MODEL.json to save the model, or --json")
    if out is not None and out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
    if structure != "arx":
        raise ParameterError(f"unknown structure {structure!r}; available: arx")
    data = _load(
        data_paths,
        inputs,
        outputs,
        ts,
        time_column,
        experiment_column,
        estimation,
        "--estimation",
    )
    result = fit_arx(
        data,
        parse_order(na, "na"),
        parse_order(nb, "nb"),
        parse_order(nk, "nk"),
        method=method,
        forgetting=forgetting,
        initial_covariance=initial_covariance,
        eps1=eps1,
        eps2=eps2,
        center=center,
        allow_unstable=allow_unstable,
        passes=passes,
        max_mse_ratio=2.0 if convergence_check else None,
    )
    record = result.estimation_record()
    if out is not None:
        save_model(result.model, out, record, overwrite=force)
    if json_out:
        print_json(model_document(result.model, record))
        return
    _print_model(result.model)
    stdout.print(
        metrics_table(
            "one-step prediction on the estimation data", [(method, result.estimation_metrics)]
        )
    )
    if out is not None:
        stdout.print(f"model written to {out}")


def _print_model(model) -> None:
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=f"{model.structure} model", title_justify="left")
    table.add_column("parameter")
    table.add_column("value", justify="right")
    for i in range(len(model.outputs)):
        for name, value in zip(model.parameter_names(i), model.parameter_vector(i), strict=True):
            table.add_row(escape(name), f"{value:.6g}")
    stdout.print(table)


def _run_model(
    mode, model_path, data_paths, rng, out, ts, time_column, experiment_column, force, json_out
):
    from blockid.data import write_table
    from blockid.errors import ParameterError
    from blockid.evaluation import evaluate
    from blockid.models import load_model

    if out is not None and out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
    model = load_model(model_path)
    data = _load(
        data_paths,
        list(model.inputs),
        list(model.outputs),
        ts or model.sampling_time,
        time_column,
        experiment_column,
        rng,
        "--range",
    )
    result = evaluate(model, data, mode)
    if out is not None:
        write_table(result.to_frame(), out, overwrite=force)
    if json_out:
        doc = {
            "model": str(model_path),
            "data": [str(p) for p in data_paths],
            "range": rng,
            **result.to_dict(),
        }
        print_json(doc)
        return
    label = "free-run simulation" if mode == "simulation" else "one-step-ahead prediction"
    stdout.print(
        metrics_table(
            f"{label} on {', '.join(map(str, data_paths))}" + (f" [{rng}]" if rng else ""),
            [(model.structure, result.metrics)],
        )
    )
    if out is not None:
        stdout.print(f"model output written to {out}")


ModelPath = Annotated[Path, typer.Argument(help="Model file written by 'blockid fit'.")]
Range = Annotated[
    str | None, typer.Option("--range", help="Samples START:STOP to use (default: all).")
]
OutCsv = Annotated[
    Path | None, typer.Option("--out", "-o", help="Write data and model output (.csv/.parquet).")
]


@app.command()
@cli_errors
def simulate(
    model_path: ModelPath,
    data_paths: DataPaths,
    rng: Range = None,
    out: OutCsv = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    experiment_column: ExperimentColumn = None,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Free-run simulation of a model on the inputs in DATA (outputs used for metrics)."""
    _run_model(
        "simulation",
        model_path,
        data_paths,
        rng,
        out,
        ts,
        time_column,
        experiment_column,
        force,
        json_out,
    )


@app.command()
@cli_errors
def predict(
    model_path: ModelPath,
    data_paths: DataPaths,
    rng: Range = None,
    out: OutCsv = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    experiment_column: ExperimentColumn = None,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """One-step-ahead prediction of a model on DATA (measured past outputs fed in)."""
    _run_model(
        "one-step",
        model_path,
        data_paths,
        rng,
        out,
        ts,
        time_column,
        experiment_column,
        force,
        json_out,
    )


def main() -> None:
    """Console-script entry point."""
    app()


if __name__ == "__main__":
    main()
