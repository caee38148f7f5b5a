"""``blockid identify``: choose structure, orders and nonlinearity from the data alone.

The search runs in :func:`blockid.workflows.identify.identify`; this command reads the
data, shows progress on a terminal, prints the ranked table (or one JSON document) and
saves the chosen model.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import (
    cli_errors,
    metrics_table,
    print_json,
    print_model,
    progress_bar,
    refuse_figures,
    refuse_model_name,
    refuse_to_overwrite,
    stderr,
    stdout,
)
from blockid.cli._data import check_arguments, load_data, select_range
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Force,
    Inputs,
    Jobs,
    Json,
    ModelOut,
    Outputs,
    PlotDir,
    Quiet,
    Reading,
    ReportFile,
    reads_data,
    shared,
)
from blockid.cli.report import write_report_option

__all__ = ["identify"]


def _progress(quiet: bool) -> tuple[Any, Any]:
    """A progress bar of the search's stages (:func:`~blockid.cli._common.progress_bar`)
    and the callback that advances it, or (None, None)."""
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    bar = progress_bar(
        quiet,
        TextColumn("{task.description:<15}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        TextColumn("{task.fields[label]}", style="dim"),
    )
    if bar is None:
        return None, None
    tasks: dict[str, Any] = {}

    def update(stage: str, done: int, total: int, label: str) -> None:
        if stage not in tasks:
            tasks[stage] = bar.add_task(stage, total=total, label="")
        bar.update(tasks[stage], completed=done, total=total, label=label[:60])

    return bar, update


@reads_data
@cli_errors
def identify(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    estimation: Annotated[
        str | None,
        shared("estimation", "Estimation samples: the only ones used to choose (default: all)."),
    ] = None,
    validation: Annotated[
        str | None,
        shared("validation", "Validation samples of DATA, reported on."),
    ] = None,
    validation_data: Annotated[
        list[Path] | None,
        typer.Option("--validation-data", metavar="FILE", help="Validation data file(s)."),
    ] = None,
    structures: Annotated[
        str | None,
        shared("structures", "Structures to search (default: all registered)."),
    ] = None,
    effort: Annotated[
        str,
        typer.Option(
            metavar="quick|standard|thorough",
            help="Size of the search (docs/identify.md); the same effort on the same data "
            "gives the same model on any machine.",
        ),
    ] = "standard",
    jobs: Jobs = None,
    scheduler: Annotated[
        str | None,
        shared(
            "scheduler",
            "Fit the candidates on a running dask cluster, e.g. tcp://host:8786 (the "
            "record is sent to each worker once; the same model as --jobs). Not with --jobs.",
        ),
    ] = None,
    time_limit: Annotated[
        float | None,
        typer.Option(
            metavar="SECONDS",
            help="Safety cap: no new fit starts after it (the result then says it was cut).",
        ),
    ] = None,
    budget: Annotated[
        float | None, typer.Option(hidden=True, help="Replaced by --effort and --time-limit.")
    ] = None,
    out: ModelOut = None,
    plot: PlotDir = None,
    report: ReportFile = None,
    reading: Reading = DEFAULT_READING,
    quiet: Quiet = False,
    force: Force = False,
    json_out: Json = False,
) -> None:
    """Search structures, orders, delays and nonlinearities; keep the best by free-run
    simulation on held-back folds of the ESTIMATION data; refit it on all of them.

    Validation data (--validation or --validation-data) are only reported on.
    """
    from blockid.data.ranges import check_disjoint
    from blockid.errors import ParameterError
    from blockid.workflows.effort import check_search

    if budget is not None:
        raise ParameterError(
            "--budget is gone: the search is a fixed amount of work (--effort quick, "
            "standard or thorough) so that it gives the same model on any machine; "
            "--time-limit SECONDS caps it",
            parameter="budget",
        )
    if validation and validation_data:
        raise ParameterError("give --validation or --validation-data, not both")
    refuse_model_name(out)
    refuse_to_overwrite(out, force)
    refuse_to_overwrite(report, force)
    names = [s.strip() for s in structures.split(",") if s.strip()] if structures else None
    check_search(names, effort, jobs=jobs, time_limit=time_limit)
    if scheduler is not None and jobs is not None:
        raise ParameterError(
            "give --jobs (worker processes here) or --scheduler (a dask cluster), not both",
            parameter="scheduler",
        )
    check_arguments(data_paths, ranges={"--estimation": estimation, "--validation": validation})
    if validation:
        check_disjoint(estimation or ":", validation)
    if validation_data:
        check_arguments(validation_data)
    whole = load_data(data_paths, inputs, outputs, reading)
    est = select_range(whole, estimation, "--estimation")
    val = select_range(whole, validation, "--validation") if validation else None
    if validation_data:
        val = load_data(validation_data, inputs, outputs, reading)
    from blockid.models import save_model
    from blockid.plotting.figures import FIT_FIGURES
    from blockid.workflows.identify import identify as run_identify

    refuse_figures(plot, FIT_FIGURES, force)
    bar, update = _progress(quiet or json_out)
    options = dict(
        structures=names, effort=effort, jobs=jobs, scheduler=scheduler, time_limit=time_limit
    )
    if bar is not None:
        with bar:
            result = run_identify(est, val, progress=update, **options)
    else:
        result = run_identify(est, val, **options)
    record = result.fit.estimation_record()
    record["identify"] = {k: v for k, v in result.to_dict().items() if k != "models"}
    if out is not None:
        save_model(result.model, out, record, overwrite=force)
    if plot is not None:
        from blockid.plotting.figures import fit_figures

        fit_figures(result.fit, est, plot, overwrite=force)
    if report is not None:
        write_report_option(
            report, data_paths=[*data_paths, *(validation_data or [])], identify=result,
            data=None if validation_data else whole, estimation=est, validation=val,
            estimation_range=estimation, validation_range=validation, force=force,
            quiet=quiet or json_out,
        )  # fmt: skip
    for note in result.warnings:  # with --json too: stderr (and in the document)
        stderr.print(f"warning: {note}", markup=False)
    if json_out:
        print_json(result.to_dict())
        return
    _print(result)
    if out is not None:
        stdout.print(f"model written to {out}")


def _print(result: Any) -> None:
    from rich.markup import escape
    from rich.table import Table

    table = Table(
        title=f"candidates by cross-validated free-run RMSE, lowest first ({result.holdout})",
        title_justify="left",
    )
    for col in ("", "structure and options", "stage", "CV RMSE", "fit %", "params", "s"):
        table.add_column(col, justify="left" if col in ("", "structure and options") else "right")
    for s in result.best_scored(15):
        table.add_row(
            "*" if s is result.selected else ("!" if s.flags else ""),
            escape(s.candidate.label),
            s.stage,
            f"{s.rmse:.4g}",
            f"{s.fit_percent:.1f}",
            str(s.n_parameters),
            f"{s.seconds:.1f}",
        )
    stdout.print(table)
    stdout.print(
        "* the selected model, refitted on all estimation data (among scores within 2 % "
        "of the best, the fewest parameters; a model beyond linear only if it beats the "
        "linear one consistently); ! flagged (see the JSON or the report)"
    )
    for flag in result.selected.flags:
        stdout.print(f"flag on the selected model: {flag}", markup=False, soft_wrap=True)
    if result.rejected:
        stdout.print(f"{len(result.rejected)} candidate(s) rejected, e.g.:")
        for s in result.rejected[:5]:
            stdout.print(f"  {s.candidate.label}: {s.reason}", markup=False, soft_wrap=True)
    print_model(result.model)
    where = "the validation data" if result.on == "validation" else "the ESTIMATION data"
    rows = [(result.selected.candidate.structure, result.simulation.metrics)]
    stdout.print(metrics_table(f"free-run simulation on {where}", rows))
    if result.one_step is not None:
        rows = [(result.selected.candidate.structure, result.one_step.metrics)]
        stdout.print(metrics_table(f"one-step prediction on {where}", rows))
    for note in result.notes:
        stdout.print(f"note: {note}", markup=False, soft_wrap=True)
    search = result.search
    cut = " (cut by the time limit)" if search.get("cut_by_time_limit") else ""
    stdout.print(
        f"search: effort {search.get('effort')}, {search.get('jobs')} job(s)"
        f"{' on ' + search['scheduler'] if search.get('scheduler') else ''}, "
        f"{result.seconds:.1f} s{cut}"
    )
