"""``blockid report`` and the ``--report FILE`` option of ``compare`` and ``identify``.

The report is built by :func:`blockid.reporting.build_report`; this module parses the
command line, runs the comparison and writes the file (atomically, an existing file
only with ``--force``).
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

from blockid.cli._common import busy, cli_errors, print_json, refuse_to_overwrite, stderr, stdout
from blockid.cli._data import check_arguments, load_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Force,
    Inputs,
    Json,
    Outputs,
    Quiet,
    Reading,
    reads_data,
    shared,
)
from blockid.cli._options import (
    ComparedStructures,
    EstimationRange,
    SharedMethod,
    ValidationRange,
    given,
    with_fit_options,
)

__all__ = [
    "REPORT_OPTIONS",
    "command_words",
    "compare_ranges",
    "report",
    "structure_names",
    "write_report_option",
]

#: What the report's figures need of every fit: the parameter trajectories of the
#: recursive methods and the standard errors (confidence bands of the blocks).
REPORT_OPTIONS = {"record_history": True, "standard_errors": True}


def command_words() -> list[str]:
    """The command line that is running, as words starting with ``blockid``.

    ``sys.argv`` when the ``blockid`` script (or ``python -m blockid``) runs; otherwise
    (the command called in-process, as by a test runner) rebuilt from the parsed
    parameters that were given on the command line, which runs the same.
    """
    script = Path(sys.argv[0])
    if script.name in ("blockid", "blockid.exe") or script.parent.name == "blockid":
        return ["blockid", *sys.argv[1:]]
    try:
        from typer._click.globals import get_current_context
    except ImportError:  # pragma: no cover - older typer depends on click
        from click import get_current_context  # type: ignore[no-redef]
    ctx = get_current_context(silent=True)
    if ctx is None:
        return ["blockid", *sys.argv[1:]]
    words = ["blockid", *ctx.command_path.split()[1:]]
    for param in ctx.command.params:
        source = ctx.get_parameter_source(param.name)
        if source is None or source.name != "COMMANDLINE":
            continue
        value = ctx.params.get(param.name)
        if param.param_type_name == "argument":
            words += [str(v) for v in (value if isinstance(value, list | tuple) else [value])]
            continue
        name = max(param.opts, key=len)
        if getattr(param, "is_flag", False):
            off = param.secondary_opts
            words.append(off[0] if (value is False and off) else name)
        elif isinstance(value, list | tuple):
            for v in value:
                words += [name, str(v)]
        else:
            words += [name, str(value)]
    return words


def write_report_option(
    path: Path,
    *,
    data_paths: Sequence[Path],
    estimation: Any,
    validation: Any = None,
    compare: Any = None,
    identify: Any = None,
    data: Any = None,
    estimation_range: str | None = None,
    validation_range: str | None = None,
    force: bool = False,
    announce: bool = True,
    quiet: bool = False,
) -> Path:
    """Build the report of a ``compare`` / ``identify`` run and write it to ``path``,
    with a spinner unless ``quiet``.

    Call :func:`~blockid.cli._common.refuse_to_overwrite` on ``path`` before the work;
    this writes atomically and replaces an existing file only with ``force``. With
    ``announce``, says where the report went on stderr (stdout may be ``--json``).
    """
    from blockid.reporting import build_report, collect_provenance, write_report

    with busy("writing the report", quiet):
        provenance = collect_provenance(data_paths, command_words())
        html = build_report(
            compare=compare,
            identify=identify,
            data=data,
            estimation=estimation,
            validation=validation,
            estimation_range=estimation_range,
            validation_range=validation_range,
            provenance=provenance,
        )
        written = write_report(html, path, overwrite=force)
        if announce:
            stderr.print(f"report written to {written}", markup=False)
    return written


def structure_names(structures: str | None) -> dict[str, list[str]]:
    """``structures=`` of :func:`~blockid.workflows.compare_structures` from the
    comma-separated ``--structures`` (not given: nothing, the default set)."""
    if structures is None:
        return {}
    return {"structures": [name.strip() for name in structures.split(",") if name.strip()]}


def compare_ranges(
    data: Any,
    estimation: str,
    validation: str,
    names: dict[str, list[str]],
    method: str | None,
    options: dict[str, Any],
    quiet: bool,
) -> tuple[Any, Any, Any]:
    """The estimation and validation ranges of ``data`` and the comparison of the
    structures fitted on the one and scored on the other (``compare`` and ``report``),
    with a spinner unless ``quiet``."""
    from blockid.data.ranges import parse_range
    from blockid.workflows import compare_structures

    est = data.select(*parse_range(estimation, "--estimation"), what="--estimation")
    val = data.select(*parse_range(validation, "--validation"), what="--validation")
    with busy("identifying and comparing the structures", quiet):
        result = compare_structures(est, val, **names, method=method, options=options)
    return est, val, result


@with_fit_options
@reads_data
@cli_errors
def report(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Outputs,
    estimation: EstimationRange,
    validation: ValidationRange,
    structures: ComparedStructures = None,
    method: SharedMethod = None,
    out: Annotated[Path, shared("out", "HTML report file to write.")] = Path("report.html"),
    reading: Reading = DEFAULT_READING,
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
    **options: Any,
) -> None:
    """Compare structures as 'blockid compare' does and write one HTML report.

    The report is a single file that opens in any browser without a network: the data
    with the estimation and validation ranges, the free-run and one-step scores of every
    model (failures with their reasons), measured against simulated output and the
    residual on the validation range, the identified nonlinear blocks (with confidence
    bands when the fit has parameter standard errors), the parameter trajectories of the
    recursive methods, and the command, data file hashes and versions that made it.
    """
    from blockid.data.ranges import check_disjoint

    refuse_to_overwrite(out, force)
    check_arguments(data_paths, ranges={"--estimation": estimation, "--validation": validation})
    check_disjoint(estimation, validation)
    data = load_data(data_paths, inputs, outputs, reading)
    opts = {**REPORT_OPTIONS, **given(options)}
    est, val, result = compare_ranges(
        data, estimation, validation, structure_names(structures), method, opts, quiet or json_out
    )
    path = write_report_option(
        out,
        data_paths=data_paths,
        compare=result,
        data=data,
        estimation=est,
        validation=val,
        estimation_range=estimation,
        validation_range=validation,
        force=force,
        announce=False,
        quiet=quiet or json_out,
    )
    if json_out:
        print_json({"report": str(path), "bytes": path.stat().st_size, **result.to_dict()})
        return
    failed = [m.structure for m in result.models if m.error]
    stdout.print(
        f"report written to {path} ({path.stat().st_size / 1e3:.0f} kB; "
        f"{len(result.models) - len(failed)} model(s)"
        + (f", failed: {', '.join(failed)}" if failed else "")
        + ")",
        markup=False,
    )
