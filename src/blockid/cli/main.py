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
    stderr,
    stdout,
)
from blockid.errors import EstimationError

__all__ = ["app", "main"]

app = typer.Typer(
    name="blockid",
    help="Identify block-oriented nonlinear models (Hammerstein, Wiener, "
    "Hammerstein-Wiener, backlash, networks) from input/output data.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        from blockid import __version__

        stdout.print(f"blockid {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version."),
    ] = False,
) -> None:
    """Identify block-oriented nonlinear models (Hammerstein, Wiener, Hammerstein-Wiener,
    backlash, networks) from input/output data."""


DataPaths = Annotated[
    list[Path],
    typer.Argument(metavar="DATA...", help="Data file(s): .csv, .tsv, .txt, .parquet or .mat."),
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


Structure = Annotated[
    str,
    typer.Option(help="arx | hammerstein | wiener | hammerstein-wiener | backlash."),
]
Method = Annotated[
    str | None,
    typer.Option(
        help="Estimator. arx: batch (default), rls, aw-rls, hierarchical-rls. "
        "hammerstein/wiener/hammerstein-wiener: simulation-error (default), key-term-rls. "
        "backlash: simulation-error (default), aw-rls."
    ),
]
Na = Annotated[str, typer.Option(help="Output lags na: N, or for ARX a matrix 'N,N;N,N'.")]
Nb = Annotated[str, typer.Option(help="Input coefficients nb (b_0..b_nb-1): N or matrix.")]
Nk = Annotated[str, typer.Option(help="Input delay nk in samples: N or matrix.")]
R1 = Annotated[int | None, typer.Option(help="Degree of the two-segment input polynomial.")]
R2 = Annotated[int | None, typer.Option(help="Degree of the output polynomial.")]
Refine = Annotated[
    bool, typer.Option(help="Refine any method's estimate on free-run simulation error.")
]
Forgetting = Annotated[
    str | None, typer.Option(help="Forgetting factor, or schedule such as 0.98:200,1.")
]
InitialCovariance = Annotated[
    float | None, typer.Option(help="P(0) scale of the recursive methods.")
]
Passes = Annotated[int | None, typer.Option(help="Passes of a recursive method over the data.")]
Eps1 = Annotated[float | None, typer.Option(help="AW-RLS weight eps1 (A8).")]
Eps2 = Annotated[float | None, typer.Option(help="AW-RLS weight eps2 (A8).")]
Center = Annotated[
    bool,
    typer.Option(help="Fit around the mean operating point (offsets kept in the model)."),
]
AllowUnstable = Annotated[
    bool, typer.Option(help="ARX: keep a model with poles outside the unit circle.")
]
ConvergenceCheck = Annotated[
    bool,
    typer.Option(
        help="ARX recursive methods: fail when the one-step MSE exceeds 2x the LS optimum."
    ),
]
PlotDir = Annotated[Path | None, typer.Option("--plot", help="Write PNG figures to this folder.")]


#: Fit options passed through from the command line as they are (None: method default).
_PASS_THROUGH = ("r1", "r2", "forgetting", "initial_covariance", "passes", "eps1", "eps2")


def _fit_options(
    structure: str,
    method: str | None,
    values: dict,
    center: bool,
    allow_unstable: bool,
    convergence_check: bool,
) -> dict:
    from blockid.errors import ParameterError

    opts = {name: parse_order(values[name], name) for name in ("na", "nb", "nk")}
    opts.update({name: values[name] for name in _PASS_THROUGH})
    if structure == "arx":
        opts.update(center=center or None, allow_unstable=allow_unstable or None)
        if not convergence_check:
            if method in (None, "batch"):
                raise ParameterError(
                    "--no-convergence-check applies to the recursive ARX methods (rls, aw-rls, "
                    "hierarchical-rls), not to batch least squares"
                )
            opts["max_mse_ratio"] = float("inf")  # check switched off
    else:
        if allow_unstable or not convergence_check:
            flag = "--allow-unstable" if allow_unstable else "--no-convergence-check"
            raise ParameterError(f"{flag} applies to ARX models only, not {structure}")
        opts["center"] = True if center else None
    return opts


@app.command()
@cli_errors
def fit(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    structure: Structure = "arx",
    method: Method = None,
    na: Na = "1",
    nb: Nb = "1",
    nk: Nk = "1",
    r1: R1 = None,
    r2: R2 = None,
    refine: Refine = False,
    forgetting: Forgetting = None,
    initial_covariance: InitialCovariance = None,
    passes: Passes = None,
    eps1: Eps1 = None,
    eps2: Eps2 = None,
    center: Center = False,
    allow_unstable: AllowUnstable = False,
    convergence_check: ConvergenceCheck = True,
    estimation: Annotated[
        str | None, typer.Option(help="Estimation samples START:STOP (0-based, stop excluded).")
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Model file to write.")] = None,
    plot: PlotDir = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    experiment_column: ExperimentColumn = None,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Identify a model from data and save it as a JSON model file."""
    from blockid.errors import ParameterError
    from blockid.fitting import fit_model
    from blockid.models import model_document, save_model

    if out is None and not json_out:
        raise ParameterError("nothing to do: give -o MODEL.json to save the model, or --json")
    if out is not None and out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
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
    values = {k: v for k, v in locals().items() if k in ("na", "nb", "nk", *_PASS_THROUGH)}
    options = _fit_options(structure, method, values, center, allow_unstable, convergence_check)
    from blockid.fitting import DEFAULT_METHOD

    chosen = method or DEFAULT_METHOD.get(structure)
    if plot is not None and chosen in ("key-term-rls", "aw-rls") and structure != "arx":
        options["record_history"] = True  # parameter trajectories for the figure
    try:
        result = fit_model(data, structure, method=method, refine=refine, **options)
    except EstimationError as exc:
        if plot is not None:
            from blockid.plotting.figures import failed_fit_figures

            for path in failed_fit_figures(exc.history, plot):
                stderr.print(
                    f"parameter trajectories up to the failure written to {path}", markup=False
                )
        raise
    record = result.estimation_record()
    if out is not None:
        save_model(result.model, out, record, overwrite=force)
    if plot is not None:
        from blockid.plotting.figures import fit_figures

        fit_figures(result, data, plot)
    if json_out:
        print_json(model_document(result.model, record))
        return
    _print_model(result.model)
    label = "one-step prediction" if result.metrics_mode == "one-step" else "free-run simulation"
    stdout.print(
        metrics_table(
            f"{label} on the estimation data", [(result.method, result.estimation_metrics)]
        )
    )
    if out is not None:
        stdout.print(f"model written to {out}")
    if plot is not None:
        stdout.print(f"figures written to {plot}/")


def _print_model(model) -> None:
    from rich.markup import escape
    from rich.table import Table

    table = Table(title=f"{model.structure} model", title_justify="left")
    table.add_column("parameter")
    table.add_column("value", justify="right")
    if hasattr(model, "parameter_names"):  # ARX
        for i in range(len(model.outputs)):
            names, values = model.parameter_names(i), model.parameter_vector(i)
            for name, value in zip(names, values, strict=True):
                table.add_row(escape(name), f"{value:.6g}")
    elif hasattr(model, "subsystems"):
        for name, sub in model.subsystems:
            table.add_row(escape(name), sub.structure)
    else:
        for name, value in model.parameters.items():
            values = value if isinstance(value, list) else [value]
            table.add_row(name, ", ".join(f"{v:.6g}" for v in values))
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
    for note in result.warnings:
        stderr.print(f"warning: {note}", markup=False)
    label = "free-run simulation" if mode == "simulation" else "one-step-ahead prediction"
    stdout.print(
        metrics_table(
            f"{label} on {', '.join(map(str, data_paths))}" + (f" [{rng}]" if rng else ""),
            [(model.structure, result.metrics)],
        )
    )
    if out is not None:
        stdout.print(f"model output written to {out}")


@app.command("fit-network")
@cli_errors
def fit_network_cmd(
    data_paths: DataPaths,
    subsystems: Annotated[
        list[str],
        typer.Option(
            "--subsystem",
            "-s",
            help="'NAME: IN[,IN] -> OUT[,OUT] | STRUCTURE key=value ...', e.g. "
            "'S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls'. Repeat, upstream first.",
        ),
    ],
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
    """Identify a network of subsystems, each from its own measured signals (paper A).

    The data must hold every signal the subsystems name (internal ones measured too).
    The network model simulates all subsystem outputs from the external inputs alone;
    use it with 'blockid simulate' and 'blockid predict' like any model.
    """
    from blockid.errors import ParameterError
    from blockid.fitting import fit_network, parse_subsystem
    from blockid.models import model_document, save_model

    if out is None and not json_out:
        raise ParameterError("nothing to do: give -o MODEL.json to save the model, or --json")
    if out is not None and out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
    specs = [parse_subsystem(text) for text in subsystems]
    external = []
    produced = {o for spec in specs for o in spec.outputs}
    for spec in specs:
        external += [i for i in spec.inputs if i not in produced and i not in external]
    data = _load(
        data_paths,
        external,
        sorted(produced, key=[o for sp in specs for o in sp.outputs].index),
        ts,
        time_column,
        experiment_column,
        estimation,
        "--estimation",
    )
    result = fit_network(data, specs)
    record = result.estimation_record()
    if out is not None:
        save_model(result.model, out, record, overwrite=force)
    if json_out:
        print_json(model_document(result.model, record))
        return
    for name, sub in result.model.subsystems:
        stdout.print(
            f"[bold]{name}[/]: {', '.join(sub.inputs)} -> {', '.join(sub.outputs)} "
            f"({sub.structure}, {record['settings']['subsystems'][name]['method']})"
        )
        _print_model(sub)
    stdout.print(
        metrics_table(
            "free-run simulation of the network on the estimation data",
            [("network", result.estimation_metrics)],
        )
    )
    if out is not None:
        stdout.print(f"model written to {out}")


@app.command()
@cli_errors
def compare(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    estimation: Annotated[str, typer.Option(help="Estimation samples START:STOP.")],
    validation: Annotated[str, typer.Option(help="Validation samples START:STOP.")],
    structures: Annotated[
        str, typer.Option(help="Comma-separated structures to identify and compare.")
    ] = "arx,hammerstein,wiener,hammerstein-wiener",
    method: Annotated[
        str | None,
        typer.Option(help="Method for the structures that offer it (others: their default)."),
    ] = None,
    na: Annotated[int, typer.Option(help="Output lags.")] = 1,
    nb: Annotated[int, typer.Option(help="Input coefficients b_0..b_nb-1.")] = 1,
    nk: Annotated[int, typer.Option(help="Input delay in samples.")] = 1,
    r1: R1 = None,
    r2: R2 = None,
    refine: Refine = False,
    forgetting: Forgetting = None,
    passes: Passes = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    experiment_column: ExperimentColumn = None,
    json_out: Json = False,
) -> None:
    """Identify several structures and compare them on validation data.

    Prints, for each model, MSE, RMSE, mean and maximum absolute error and fit % of
    free-run simulation and of one-step prediction on the validation range.
    """
    from blockid.data import parse_range
    from blockid.workflows import compare_structures

    data = _load(data_paths, inputs, outputs, ts, time_column, experiment_column, None, "")
    est = data.select(*parse_range(estimation, "--estimation"), what="--estimation")
    val = data.select(*parse_range(validation, "--validation"), what="--validation")
    options = {
        "na": na,
        "nb": nb,
        "nk": nk,
        "r1": r1,
        "r2": r2,
        "forgetting": forgetting,
        "passes": passes,
        "refine": refine or None,
    }
    result = compare_structures(
        est,
        val,
        [s.strip() for s in structures.split(",") if s.strip()],
        method=method,
        options={k: v for k, v in options.items() if v is not None},
    )
    if json_out:
        print_json(result.to_dict())
        return
    for mode, title in (("simulation", "free-run simulation"), ("one_step", "one-step prediction")):
        rows = [
            (f"{m.structure} ({m.method})", getattr(m, mode).metrics)
            for m in result.models
            if getattr(m, mode) is not None
        ]
        stdout.print(metrics_table(f"{title} on the validation range {validation}", rows))
    for m in result.models:
        if m.error:
            stdout.print(f"[red]{m.structure} ({m.method}) failed:[/] {m.error}", soft_wrap=True)
        for note in m.simulation.warnings if m.simulation is not None else []:
            stderr.print(f"warning: {m.structure}: {note}", markup=False)
        if m.one_step_error:
            stdout.print(
                f"{m.structure}: no one-step prediction: {m.one_step_error}",
                soft_wrap=True,
                markup=False,
            )


ModelPath = Annotated[
    Path, typer.Argument(metavar="MODEL", help="Model file written by 'blockid fit'.")
]
Range = Annotated[
    str | None, typer.Option("--range", help="Samples START:STOP to use (default: all).")
]
OutCsv = Annotated[
    Path | None, typer.Option("--out", "-o", help="Write data and model output (.csv/.parquet).")
]


def _model_command(mode: str, name: str, doc: str) -> None:
    """Register ``simulate`` / ``predict``: the same options, another mode."""

    @cli_errors
    def command(
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
        _run_model(
            mode,
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

    command.__doc__ = doc
    app.command(name)(command)


_model_command(
    "simulation",
    "simulate",
    "Free-run simulation of a model on the inputs in DATA (outputs used for metrics).",
)
_model_command(
    "one-step",
    "predict",
    "One-step-ahead prediction of a model on DATA (measured past outputs fed in).",
)


@app.command()
@cli_errors
def demo(
    output_dir: Annotated[
        Path, typer.Option("--output-dir", help="Folder for the data, models and figures.")
    ] = Path("demo-output"),
    seed: Annotated[int, typer.Option(help="Random seed of the simulated plant.")] = 0,
    json_out: Json = False,
) -> None:
    """Run the built-in example: paper B's experiment on the simulated excavator arm.

    Same as 'blockid reproduce electrohydraulic', and keeps the data, the best model of
    every structure and the figures in the output folder.
    """
    from blockid.workflows.demo import run_demo

    result = run_demo(output_dir, seed=seed)
    if json_out:
        print_json(result.to_dict())
        return
    _print_electrohydraulic(result)
    stdout.print(f"data, models, figures and results.json written to {output_dir}/")


reproduce_app = typer.Typer(
    help="Reproduce the seed papers' experiments on blockid's simulated plants.",
    no_args_is_help=True,
)
app.add_typer(reproduce_app, name="reproduce")

FiguresDir = Annotated[Path, typer.Option("--figures", help="Folder for the PNG figures.")]
Seed = Annotated[int, typer.Option(help="Random seed: the same seed gives the same run.")]


@reproduce_app.command("windtunnel")
@cli_errors
def reproduce_windtunnel_cmd(
    seed: Seed = 0,
    figures: FiguresDir = Path("reproduce-windtunnel"),
    json_out: Json = False,
) -> None:
    """Paper A: block-oriented network vs conventional linear model (Table 2)."""
    from blockid.workflows.reproduce_windtunnel import PAPER_TABLE, reproduce_windtunnel

    result = reproduce_windtunnel(seed=seed, figures_dir=figures)
    if json_out:
        print_json(result.to_dict())
        return
    from rich.table import Table

    table = Table(
        title="Paper A, Table 2 form: free-run simulation from u1, u2 on the validation record",
        title_justify="left",
    )
    for col in ("condition", "model", "estimator", "RMSE P0", "RMSE Ma", "max|e| P0", "max|e| Ma"):
        table.add_column(col, justify="right" if "|" in col or "RMSE" in col else "left")
    for row in result.table:
        if "error" in row:
            table.add_row(
                row["condition"], row["model"], row["estimator"], "failed", "see below", "", ""
            )
            continue
        table.add_row(
            row["condition"],
            row["model"],
            row["estimator"],
            f"{row['rmse']['y1']:.4f}",
            f"{row['rmse']['y2']:.5f}",
            f"{row['max_abs_error']['y1']:.4f}",
            f"{row['max_abs_error']['y2']:.5f}",
        )
    for row in PAPER_TABLE:
        table.add_row(
            row["condition"],
            row["model"],
            "paper A (measured data)",
            f"{row['rmse']['y1']:.4f}",
            f"{row['rmse']['y2']:.5f}",
            f"{row['max_abs_error']['y1']:.4f}",
            f"{row['max_abs_error']['y2']:.5f}",
        )
    stdout.print(table)
    for row in result.table:
        if "error" in row:
            stdout.print(
                f"{row['condition']} {row['estimator']}: {row['error']}",
                markup=False,
                soft_wrap=True,
            )
    params = Table(
        title="identified actuator parameters (truth of the simulator)", title_justify="left"
    )
    for col in (
        "condition",
        "estimator",
        "a1 S1",
        "b0 S1",
        "m_left",
        "c_left",
        "m_right",
        "c_right",
        "a1 S2",
        "a2 S2",
    ):
        params.add_column(col)
    for condition, by_est in result.parameters.items():
        tr = result.truth[condition]
        rows = [("truth", tr)] + list(by_est.items())
        for est, p in rows:
            s1, s2 = p["S1"], p["S2"]
            params.add_row(
                condition,
                est,
                f"{s1['a'][0]:.4f}",
                f"{s1['b'][0]:.4f}",
                *(f"{s2[k]:.4f}" for k in ("m_left", "c_left", "m_right", "c_right")),
                f"{s2['a'][0]:.4f}",
                f"{s2['a'][1]:.4f}",
            )
    stdout.print(params)
    stdout.print(f"figures written to {figures}/")


@reproduce_app.command("electrohydraulic")
@cli_errors
def reproduce_electrohydraulic_cmd(
    seed: Seed = 0,
    figures: FiguresDir = Path("reproduce-electrohydraulic"),
    validation_bandwidth: Annotated[
        str,
        typer.Option(
            help="Corner frequency [Hz] of the validation command's low-pass, below 10; "
            "'none' for the step-like moves that ask the models to extrapolate in frequency.",
        ),
    ] = "0.5",
    json_out: Json = False,
) -> None:
    """Paper B: Hammerstein-Wiener vs Hammerstein, Wiener and ARX (Table 2)."""
    from blockid.workflows.reproduce_electrohydraulic import reproduce_electrohydraulic

    bandwidth = _bandwidth(validation_bandwidth)
    result = reproduce_electrohydraulic(
        seed=seed, figures_dir=figures, validation_bandwidth=bandwidth
    )
    if json_out:
        print_json(result.to_dict())
        return
    _print_electrohydraulic(result)
    stdout.print(f"figures written to {figures}/")


def _bandwidth(text: str) -> float | None:
    """``--validation-bandwidth``: a number (its range is checked by the plant) or ``none``."""
    from blockid.errors import ParameterError

    if text.strip().lower() == "none":
        return None
    try:
        return float(text)
    except ValueError:
        raise ParameterError(
            f"--validation-bandwidth must be a frequency in Hz or 'none', got {text!r}"
        ) from None


def _print_electrohydraulic(result) -> None:
    from rich.table import Table

    from blockid.workflows.reproduce_electrohydraulic import PAPER_MSE

    band = result.validation_bandwidth
    table = Table(
        title="Paper B, Table 2 form: MSE of free-run simulation on the validation trajectory "
        + ("(step-like command) " if band is None else f"(command low-passed at {band:g} Hz) ")
        + "[(rad/s)^2]",
        title_justify="left",
    )
    for col in ("model", "estimator", "MSE", "fit %", "best", "paper B MSE"):
        table.add_column(col, justify="left" if col in ("model", "estimator") else "right")
    for row in result.table:
        best = result.best.get(row["model"], {}).get("estimator") == row["estimator"]
        if "error" in row:
            table.add_row(row["model"], row["estimator"], "failed", "", "", "")
            continue
        table.add_row(
            row["model"],
            row["estimator"],
            f"{row['mse']['velocity']:.4g}",
            f"{row['fit_percent']['velocity']:.1f}",
            "*" if best else "",
            f"{PAPER_MSE[row['model']]:.4f}" if best else "",
        )
    stdout.print(table)
    if "hammerstein-wiener" in result.best:
        red = result.reductions()
        stdout.print(
            "best H-W MSE below: "
            + ", ".join(f"{s} {100 * r:.0f} %" for s, r in red.items())
            + "  (paper B: hammerstein 13 %, wiener 54 %, arx 58 %)"
        )
    for row in result.table:
        if "error" in row:
            stdout.print(f"{row['model']} {row['estimator']}: {row['error']}", markup=False)


EXAMPLES = ("electrohydraulic", "windtunnel-110kPa", "windtunnel-130kPa")


@app.command("example-data")
@cli_errors
def example_data(
    name: Annotated[str, typer.Argument(help=f"One of: {', '.join(EXAMPLES)}.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="File to write (.csv/.parquet).")],
    seed: Seed = 0,
    force: Force = False,
) -> None:
    """Write a record of a built-in simulated plant, to try the other commands on.

    One continuous record: the estimation experiment followed by the validation
    experiment (the ranges to use are printed). electrohydraulic: columns t, current,
    velocity (estimation: the averaged multisine runs; validation: a general trajectory).
    windtunnel-*: t, u1, u2, v1, v2, y1, y2 at that operating condition.
    """
    import numpy as np
    import pandas as pd

    from blockid.data import write_table
    from blockid.errors import ParameterError

    if name not in EXAMPLES:
        raise ParameterError(f"unknown example {name!r}; choose one of {', '.join(EXAMPLES)}")
    if out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
    if name == "electrohydraulic":
        from blockid.plants.electrohydraulic import electrohydraulic_experiment

        exp = electrohydraulic_experiment(seed=seed)
        parts = {k: exp[k][["t", "current", "velocity"]] for k in ("estimation", "validation")}
    else:
        from blockid.plants.windtunnel import windtunnel_experiment

        condition = name.split("-", 1)[1]
        parts = {
            k: windtunnel_experiment(condition, seed=seed, kind=k).drop(columns=["x_true"])
            for k in ("estimation", "validation")
        }
    frame = pd.concat(list(parts.values()), ignore_index=True)
    dt = float(parts["estimation"]["t"].iloc[1] - parts["estimation"]["t"].iloc[0])
    frame["t"] = np.arange(len(frame)) * dt
    write_table(frame, out, overwrite=force)
    n_est = len(parts["estimation"])
    stdout.print(
        f"{name} (seed {seed}) written to {out}: estimation record 0:{n_est}, "
        f"validation record {n_est}:{len(frame)} (use with --estimation/--validation)"
    )


def main() -> None:
    """Console-script entry point."""
    app()


if __name__ == "__main__":
    main()
