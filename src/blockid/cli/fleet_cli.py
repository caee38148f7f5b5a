"""``blockid fleet``: one model per record for many records, in parallel on dask.

Parses, expands the file patterns, calls :func:`blockid.workflows.fleet.fit_fleet` and
prints its summary (one JSON document with ``--json``). Progress goes to a terminal's
stderr only. dask is optional: without it the command says how to install it.
"""

from __future__ import annotations

import glob
import inspect
from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import cli_errors, print_json, progress_bar, stderr, stdout
from blockid.cli._data import check_arguments
from blockid.cli._flags import (
    Force,
    Inputs,
    Jobs,
    Json,
    Outputs,
    Quiet,
    SamplingTime,
    TimeColumn,
    shared,
)
from blockid.cli._options import (
    DEFAULT_STRUCTURE,
    Method,
    Structure,
    given,
    structures_help,
    with_fit_options,
)
from blockid.errors import ParameterError

__all__ = ["fleet"]

Patterns = Annotated[
    list[str],
    typer.Argument(
        metavar="RECORDS",
        help="Data files or quoted patterns ('logs/*.csv'); one record per file.",
    ),
]
OutDir = Annotated[
    Path,
    shared("out", "Folder of the model files and summary.", metavar="DIR"),
]
#: ``--workers``: the old name of ``--jobs`` (hidden; still taken).
Workers = Annotated[
    int | None,
    typer.Option(
        metavar="N", min=1, help="The old name of --jobs.", hidden=True, show_default=False
    ),
]
Scheduler = Annotated[
    str | None,
    shared(
        "scheduler",
        "Use a running dask cluster, e.g. tcp://host:8786 (data on shared storage).",
    ),
]


def _expand(patterns: list[str]) -> list[str]:
    files: list[str] = []
    for pattern in patterns:
        found = sorted(glob.glob(pattern)) if glob.has_magic(pattern) else [pattern]
        if not found:
            raise ParameterError(f"no file matches {pattern!r}")
        files += [f for f in found if f not in files]
    return files


@with_fit_options
@cli_errors
def fleet(
    patterns: Patterns,
    inputs: Inputs,
    outputs: Outputs,
    out: OutDir,
    structure: Structure = DEFAULT_STRUCTURE,
    method: Method = None,
    jobs: Jobs = None,
    scheduler: Scheduler = None,
    ts: SamplingTime = None,
    time_column: TimeColumn = None,
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
    workers: Workers = None,
    **options: Any,
) -> None:
    """Fit one model per record, many records in parallel (dask.distributed).

    Every record (one data file) is fitted with the same structure, method and options,
    as 'blockid fit' would, one task per record on a local cluster of --jobs
    processes or on a running cluster (--scheduler). Writes DIR/<record>.json per
    record and DIR/summary.csv and DIR/summary.parquet (file, structure, method,
    status, error, seconds, samples, rmse and fit % per output). A record that fails is
    an error row; the others go on. A rerun skips records whose model file exists,
    unless --force. Exit status 1 when some record failed.
    """
    files = _expand(patterns)
    check_arguments(structure=structure, method=method, options=given(options))
    if workers is not None:  # --workers, the old name: taken, with a word on stderr
        if jobs is not None:
            raise ParameterError("give --jobs, not also --workers (its old name)")
        jobs = workers
        stderr.print("note: --workers is now --jobs (identify's name)")
    from blockid.workflows.effort import check_jobs

    check_jobs(jobs)
    from blockid.data.dataset import _check_sampling_time
    from blockid.workflows.fleet import fit_fleet

    _check_sampling_time(ts)  # every record would fail on it: refuse before the cluster starts

    read = {"sampling_time": ts, "time_column": time_column}
    bar = progress_bar(quiet or json_out)
    task = None if bar is None else bar.add_task("fitting records", total=len(files))
    written: list[str] = []  # model files of this run, for the message on Ctrl-C

    def on_result(row: dict[str, Any]) -> None:
        if row["status"] == "ok":
            written.append(row["file"])
        if bar is not None:
            bar.advance(task)

    if bar is not None:
        bar.start()
    try:
        result = fit_fleet(
            files,
            out,
            structure,
            inputs,
            outputs,
            method=method,
            options=given(options),
            read_options={k: v for k, v in read.items() if v is not None},
            jobs=jobs,
            scheduler=scheduler,
            force=force,
            on_result=on_result,
        )
    except ImportError as exc:  # dask missing: the library says what to install
        stderr.print(f"error: {exc}", markup=False)
        raise typer.Exit(code=2) from None
    except KeyboardInterrupt:
        stderr.print(
            f"interrupted: {len(written)} model file(s) written to {out}/ before it, no "
            "summary; run the same command again to fit the rest (records with a model "
            "file are skipped)",
            markup=False,
        )
        raise typer.Exit(code=130) from None
    finally:
        if bar is not None:
            bar.stop()
    if json_out:
        print_json(result.to_dict())
    else:
        _print(result)
    if result.counts()["error"]:
        raise typer.Exit(code=1)


fleet.__doc__ = f"{inspect.cleandoc(fleet.__doc__ or '')}\n\n{structures_help()}"


def _print(result: Any) -> None:
    counts = result.counts()
    stdout.print(
        f"{len(result.rows)} records: {counts['ok']} fitted, {counts['error']} failed, "
        f"{counts['skipped']} skipped (model file exists; --force refits) in "
        f"{result.seconds:.1f} s on {result.workers} worker(s); models and summary in "
        f"{result.out_dir}/",
        markup=False,
    )
    for row in result.rows:
        if row["status"] == "error":
            error = row["error"]  # most errors name the file already
            where = "" if error.startswith(row["file"]) else f"{row['file']}: "
            stdout.print(f"failed: {where}{error}", markup=False)
