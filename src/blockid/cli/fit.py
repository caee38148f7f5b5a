"""``blockid fit``, ``compare`` and ``fit-network``: identify models from data.

The estimator flags of ``fit`` and ``compare`` are generated from the registry
(:mod:`blockid.cli._options`); their values go to the library as typed.
"""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import (
    busy,
    cli_errors,
    metrics_table,
    print_json,
    print_model,
    refuse_figures,
    refuse_model_name,
    refuse_to_overwrite,
    stderr,
    stdout,
)
from blockid.cli._data import check_arguments, load_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Estimation,
    Force,
    Inputs,
    Json,
    ModelOut,
    Outputs,
    PlotDir,
    Quiet,
    Reading,
    ReportFile,
    reads_data,
)
from blockid.cli._options import (
    DEFAULT_STRUCTURE,
    ComparedStructures,
    EstimationRange,
    Method,
    SharedMethod,
    Structure,
    ValidationRange,
    given,
    structures_help,
    with_fit_options,
)
from blockid.cli.report import (
    REPORT_OPTIONS,
    compare_ranges,
    structure_names,
    write_report_option,
)

__all__ = ["compare", "fit", "fit_network"]


def _check_output(out: Path | None, json_out: bool, force: bool) -> None:
    from blockid.errors import ParameterError

    if out is None and not json_out:
        raise ParameterError("nothing to do: give -o MODEL.json to save the model, or --json")
    refuse_model_name(out)
    refuse_to_overwrite(out, force)


@with_fit_options
@reads_data
@cli_errors
def fit(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    structure: Structure = DEFAULT_STRUCTURE,
    method: Method = None,
    estimation: Estimation = None,
    out: ModelOut = None,
    plot: PlotDir = None,
    reading: Reading = DEFAULT_READING,
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
    **options: Any,
) -> None:
    """Identify a model from data and save it as a JSON model file."""
    _check_output(out, json_out, force)
    options = given(options)
    check_arguments(
        data_paths, structure=structure, method=method, options=options,
        ranges={"--estimation": estimation},
    )  # fmt: skip
    data = load_data(data_paths, inputs, outputs, reading, estimation)
    from blockid.errors import EstimationError
    from blockid.fitting import fit_model
    from blockid.fitting.dispatch import accepted_options
    from blockid.models import model_document, save_model
    from blockid.plotting.figures import FIT_FIGURES

    refuse_figures(plot, FIT_FIGURES, force)
    if plot is not None and "record_history" in accepted_options(structure, method):
        options["record_history"] = True  # parameter trajectories for the figure
    try:
        with busy(f"fitting {structure} ({method or 'default method'})", quiet or json_out):
            result = fit_model(data, structure, method=method, **options)
    except EstimationError as exc:
        if plot is not None:
            from blockid.plotting.figures import failed_fit_figures

            for path in failed_fit_figures(exc.history, plot, overwrite=force):
                stderr.print(
                    f"parameter trajectories up to the failure written to {path}", markup=False
                )
        raise
    record = result.estimation_record()
    if out is not None:
        save_model(result.model, out, record, overwrite=force)
    if plot is not None:
        from blockid.plotting.figures import fit_figures

        fit_figures(result, data, plot, overwrite=force)
    for note in result.settings.get("warnings", []):  # with --json too: stderr
        stderr.print(f"warning: {note}", markup=False)
    if json_out:
        print_json(model_document(result.model, record))
        return
    if not quiet:
        print_model(result.model)
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


fit.__doc__ = f"{inspect.cleandoc(fit.__doc__ or '')}\n\n{structures_help()}"


@with_fit_options
@reads_data
@cli_errors
def compare(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    estimation: EstimationRange,
    validation: ValidationRange,
    structures: ComparedStructures = None,
    method: SharedMethod = None,
    reading: Reading = DEFAULT_READING,
    json_out: Json = False,
    report: ReportFile = None,
    force: Force = False,
    quiet: Quiet = False,
    **options: Any,
) -> None:
    """Identify several structures and compare them on validation data.

    Prints, for each model, MSE, RMSE, mean and maximum absolute error and fit % of
    free-run simulation and of one-step prediction on the validation range. Each
    structure takes the estimator options it uses and leaves the others.
    """
    from blockid.data.ranges import check_disjoint
    from blockid.fitting.registry import COMPARED_BY_DEFAULT, check_compared

    refuse_to_overwrite(report, force)
    check_arguments(data_paths, ranges={"--estimation": estimation, "--validation": validation})
    check_disjoint(estimation, validation)
    names = structure_names(structures)
    check_compared(names.get("structures", COMPARED_BY_DEFAULT), method)
    data = load_data(data_paths, inputs, outputs, reading)
    opts = given(options)
    if report is not None:
        opts = {**REPORT_OPTIONS, **opts}
    est, val, result = compare_ranges(
        data, estimation, validation, names, method, opts, quiet or json_out
    )
    if report is not None:
        write_report_option(
            report, data_paths=data_paths, compare=result, data=data, estimation=est,
            validation=val, estimation_range=estimation, validation_range=validation,
            force=force, quiet=quiet or json_out,
        )  # fmt: skip
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
        if m.residuals is not None:
            line = f"{m.structure}: residual tests {m.residuals.verdict()}"
            stdout.print(line, soft_wrap=True, markup=False)


@reads_data
@cli_errors
def fit_network(
    data_paths: DataPaths,
    subsystems: Annotated[
        list[str],
        typer.Option(
            "--subsystem",
            "-s",
            metavar="SPEC",
            help="'NAME: IN[,IN] -> OUT[,OUT] | STRUCTURE key=value ...', e.g. "
            "'S1: u1 -> v1 | arx na=1 nb=1 nk=1 method=rls'; the keys are the "
            "options of 'blockid fit' (na, forgetting, input-block, ...). "
            "Repeat, upstream first.",
        ),
    ],
    estimation: Estimation = None,
    out: ModelOut = None,
    reading: Reading = DEFAULT_READING,
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Identify a network of subsystems, each from its own measured signals (paper A).

    The data must hold every signal the subsystems name (internal ones measured too).
    The network model simulates all subsystem outputs from the external inputs alone;
    use it with 'blockid simulate' and 'blockid predict' like any model.
    """
    _check_output(out, json_out, force)
    check_arguments(data_paths, ranges={"--estimation": estimation})
    from blockid.fitting import parse_subsystem
    from blockid.fitting.network import fit_network as fit
    from blockid.fitting.network import network_signals
    from blockid.models import model_document, save_model

    specs = [parse_subsystem(text) for text in subsystems]
    inputs, outputs = network_signals(specs)
    data = load_data(data_paths, inputs, outputs, reading, estimation)
    with busy(f"fitting the network's {len(specs)} subsystem(s)", quiet or json_out):
        result = fit(data, specs)
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
        print_model(sub)
    stdout.print(
        metrics_table(
            "free-run simulation of the network on the estimation data",
            [("network", result.estimation_metrics)],
        )
    )
    if out is not None:
        stdout.print(f"model written to {out}")
