"""The flags that several commands take, each declared once.

:data:`SHARED` holds every such flag's names and placeholder; :func:`shared` is the only
place that turns one into a ``typer.Option``, and the flags that mean the same on every
command are declared here whole (``Force``, ``Estimation``, ``ModelOut``...). A flag
whose meaning depends on the command (``--out`` writes a model, a report, a folder...)
gets its help from the command, its names from here. ``tests/cli/test_flags.py`` walks
every command and fails on a flag of this table made anywhere else. Plain typer, no
NumPy: the command line builds these before it imports anything numerical.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, NamedTuple

import typer

__all__ = [
    "DEFAULT_READING",
    "SHARED",
    "DataPaths",
    "Estimation",
    "ExperimentColumn",
    "Force",
    "FolderForce",
    "Inputs",
    "Json",
    "ModelOut",
    "Outputs",
    "Jobs",
    "ModelPath",
    "PlotDir",
    "Reading",
    "ReportFile",
    "Quiet",
    "SampleRange",
    "SamplingTime",
    "Seed",
    "TimeColumn",
    "reads_data",
    "shared",
]

#: Flags of several commands: parameter name -> (flag names, placeholder).
SHARED: dict[str, tuple[tuple[str, ...], str | None]] = {
    "out": (("--out", "-o"), "FILE"),
    "plot": (("--plot",), "DIR"),
    "estimation": (("--estimation",), "START:STOP"),
    "validation": (("--validation",), "START:STOP"),
    "seed": (("--seed",), "N"),
    "force": (("--force",), None),
    "structure": (("--structure",), "NAME"),
    "structures": (("--structures",), "NAME,NAME.."),
    "method": (("--method",), "NAME"),
    "outputs": (("--output", "-y"), "NAME"),
    "inputs": (("--input", "-u"), "NAME"),
    "json_out": (("--json",), None),
    "quiet": (("--quiet", "-q"), None),
    "ts": (("--ts",), "SECONDS"),
    "time_column": (("--time-column",), "NAME"),
    "experiment_column": (("--experiment-column",), "NAME"),
    "report": (("--report",), "FILE"),
    "scheduler": (("--scheduler",), "ADDRESS"),
    "jobs": (("--jobs",), "N"),
    "range": (("--range",), "START:STOP"),
    "periods": (("--periods",), "N"),
    "confidence": (("--confidence",), "LEVEL"),
}

#: (parameter name, help) of every option :func:`shared` made: the test's evidence that
#: a command's shared flag came from here.
MADE: set[tuple[str, str]] = set()


def shared(name: str, help: str, *, metavar: str | None = None, **kwargs: Any) -> Any:
    """The ``typer.Option`` of shared flag ``name`` (:data:`SHARED`) with this command's
    ``help`` (and ``metavar`` where the command's value differs: ``--out DIR``)."""
    names, placeholder = SHARED[name]
    MADE.add((name, help))
    if metavar or placeholder:
        kwargs["metavar"] = metavar or placeholder
    return typer.Option(*names, help=help, **kwargs)


# ---------------------------------------------------------------- the same on every command
DataPaths = Annotated[
    list[Path],
    typer.Argument(metavar="DATA", help="Data file(s): .csv, .tsv, .txt, .parquet or .mat."),
]
#: The model file read by ``simulate``, ``predict``, ``residuals`` and ``export``.
ModelPath = Annotated[
    Path, typer.Argument(metavar="MODEL", help="Model file written by 'blockid fit'.")
]
Inputs = Annotated[list[str], shared("inputs", "Input column; repeat for several inputs.")]
Outputs = Annotated[list[str], shared("outputs", "Output column; repeat for several outputs.")]
SamplingTime = Annotated[
    float | None, shared("ts", "Sampling time in seconds.", show_default=False)
]
TimeColumn = Annotated[
    str | None, shared("time_column", "Column of sample times (sampling time inferred).")
]
ExperimentColumn = Annotated[
    str | None, shared("experiment_column", "Column labelling the experiment of each row.")
]
Force = Annotated[bool, shared("force", "Replace an existing output file.")]
#: ``--force`` of the commands that write a folder of results.
FolderForce = Annotated[
    bool, shared("force", "Write into a folder that is not empty (files replaced).")
]
Json = Annotated[bool, shared("json_out", "Print one JSON document on stdout.")]
#: ``--jobs``: the worker processes of this machine (identify's search, fleet's cluster),
#: one name and one default (``workflows.effort.check_jobs``).
Jobs = Annotated[
    int | None,
    shared(
        "jobs",
        "Worker processes on this machine, at most 64 (default: every core, at most 64).",
        show_default=False,
    ),
]
#: ``--quiet`` of every command that shows progress.
Quiet = Annotated[
    bool,
    shared(
        "quiet",
        "No progress on stderr (there is none when stderr is not a terminal, nor with --json); "
        "fit: no parameter table either; simulate, predict: nothing on stdout (files and "
        "warnings as without it).",
    ),
]
Seed = Annotated[
    int, shared("seed", "Random seed (>= 0): the same seed gives the same run.", min=0)
]
Estimation = Annotated[
    str | None,
    shared("estimation", "Estimation samples (0-based, stop excluded; default: all)."),
]
#: ``--range`` of the commands that read one span of the data.
SampleRange = Annotated[str | None, shared("range", "Samples to use (default: all).")]
ModelOut = Annotated[Path | None, shared("out", "Model file to write.")]
PlotDir = Annotated[Path | None, shared("plot", "Write PNG figures to this folder.")]
#: ``--report FILE`` of ``compare`` and ``identify``.
ReportFile = Annotated[
    Path | None,
    shared("report", "Also write a self-contained HTML report (figures embedded) to FILE."),
]


class Reading(NamedTuple):
    """How a command reads its DATA files: ``--ts``, ``--time-column`` and
    ``--experiment-column``, the flags :func:`reads_data` gives it."""

    ts: float | None = None
    time_column: str | None = None
    experiment_column: str | None = None


#: Every reading flag left out (the default of a command's ``reading``).
DEFAULT_READING = Reading()

#: The flags of :class:`Reading`, in the order a command shows them.
_READING = {"ts": SamplingTime, "time_column": TimeColumn, "experiment_column": ExperimentColumn}


def reads_data(command: Callable[..., Any]) -> Callable[..., Any]:
    """Give ``command``'s parameter ``reading`` (a :class:`Reading`) as its three flags,
    in its place on the command line, bundled again when the command runs."""
    signature = inspect.signature(command, eval_str=True)
    parameters = []
    for p in signature.parameters.values():
        if p.name != "reading":
            parameters.append(p)
            continue
        for name, annotation in _READING.items():
            parameters.append(p.replace(name=name, annotation=annotation, default=None))

    @functools.wraps(command)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        reading = Reading(*(kwargs.pop(name, None) for name in _READING))
        return command(*args, reading=reading, **kwargs)

    wrapper.__signature__ = signature.replace(parameters=parameters)  # type: ignore[attr-defined]
    return wrapper
