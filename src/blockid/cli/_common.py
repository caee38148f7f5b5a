"""What every command shares: consoles, error reporting, JSON and tables (the data
files and their checks: :mod:`blockid.cli._data`).

Library errors name Python parameters (``exc.parameter``); :func:`flag` maps them to
this command line's flags, so that a message always says what to change on the line.
"""

from __future__ import annotations

import contextlib
import functools
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from blockid.errors import BlockidError, ParameterError
from blockid.fitting.registry import OPTIONS, option_flag

__all__ = [
    "busy",
    "check_writable",
    "cli_errors",
    "error_line",
    "flag",
    "flagged",
    "metrics_table",
    "print_json",
    "print_model",
    "progress_bar",
    "progress_shown",
    "refuse_to_overwrite",
    "stderr",
    "stdout",
]

# rich falls back to 80 columns when writing to a pipe or file, which truncates numbers
# in tables; use a wide console there (a terminal keeps its own width). No emoji codes:
# a range such as 0:100:2 in a message stays as typed.
stdout = Console(
    highlight=False, emoji=False, soft_wrap=True, width=None if sys.stdout.isatty() else 160
)
stderr = Console(
    stderr=True,
    highlight=False,
    emoji=False,
    soft_wrap=True,
    width=None if sys.stderr.isatty() else 400,
)

#: Flags of the library parameters that are not estimator options (those are
#: :func:`~blockid.fitting.registry.option_flag` of their name).
FLAGS = {
    "sampling_time": "--ts",
    "time_column": "--time-column",
    "experiment_column": "--experiment-column",
    "inputs": "--input",
    "outputs": "--output",
    "overwrite": "--force",
    "estimation": "--estimation",
    "validation": "--validation",
    "structure": "--structure",
    "structures": "--structures",
    "method": "--method",
    "validation_bandwidth": "--validation-bandwidth",
    "initial_samples": "--initial-samples",
    "effort": "--effort",
    "jobs": "--jobs",
    "time_limit": "--time-limit",
}


def flag(parameter: str | None) -> str | None:
    """The flag of a library parameter on this command line (None: it has none)."""
    if parameter in FLAGS:
        return FLAGS[parameter]
    return option_flag(parameter) if parameter in OPTIONS else None


def error_line(exc: BlockidError) -> str:
    """``error: <message>``, naming the flag of the parameter at fault if it does not."""
    message = " ".join(str(exc).split())
    name = flag(getattr(exc, "parameter", None))
    if name is not None and name not in message:
        message += f" (option {name})"
    return f"error: {message}"


@contextlib.contextmanager
def flagged(flag_of: Callable[[str], str | None]) -> Iterator[None]:
    """Within: a library error names this command's flag of its parameter (``flag_of``:
    parameter -> flag, None where the command has none), unless its message does."""
    try:
        yield
    except BlockidError as exc:
        name = flag_of(exc.parameter) if exc.parameter else None
        if name is None or name in str(exc):
            raise
        raise type(exc)(f"{exc} (option {name})") from None


def cli_errors(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Turn blockid errors into one readable line on stderr and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except BlockidError as exc:
            stderr.print(error_line(exc), soft_wrap=True, markup=False)
            raise typer.Exit(code=2) from None
        except KeyboardInterrupt:
            stderr.print("interrupted; no output file was written")
            raise typer.Exit(code=130) from None
        except OSError as exc:  # e.g. stdout on a full disk or a closed pipe
            where = exc.filename or "standard output"
            stderr.print(f"error: cannot write {where}: {exc.strerror or exc}", markup=False,
                         soft_wrap=True)  # fmt: skip
            _quiet_stdout()
            raise typer.Exit(code=1) from None

    return wrapper


def _quiet_stdout() -> None:
    """Standard output to the null device: the interpreter's last flush of a stdout that
    failed would print a second error at exit."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):  # no real file descriptor (a test runner)
        pass


def progress_shown(quiet: bool) -> bool:
    """Whether a command shows progress: on a terminal's stderr, unless ``quiet``.

    Commands pass ``quiet or json_out``: with ``--json`` nothing but the document is
    written, and progress never goes to stdout.
    """
    return not quiet and sys.stderr.isatty()


def busy(what: str, quiet: bool = False) -> Any:
    """A spinner on stderr while ``what`` runs, when :func:`progress_shown` (else a
    context that does nothing)."""
    if not progress_shown(quiet):
        return contextlib.nullcontext()
    return stderr.status(f"{what} ...", spinner="dots")


def progress_bar(quiet: bool, *columns: Any) -> Any:
    """A rich progress bar on stderr (``columns``: rich's default without), cleared when
    done, when :func:`progress_shown`; else None."""
    if not progress_shown(quiet):
        return None
    from rich.progress import Progress

    return Progress(*columns, console=stderr, transient=True)


def refuse_to_overwrite(out: Path | None, force: bool) -> None:
    """Stop before any work when ``out`` exists and ``--force`` was not given (a device,
    a pipe or a link to one, such as ``/dev/stdout``, is written through, not replaced:
    no need to force it)."""
    from blockid.data.files import is_stream

    if out is None or is_stream(out):
        return
    if out.exists() and not force:
        raise ParameterError(f"{out} exists; pass --force to replace it")
    check_writable(out)


def check_writable(out: Path) -> None:
    """Stop before any work when ``out`` could not be written at the end: its folder is
    missing or not writable (a search of minutes must not end in "cannot write")."""
    import os

    folder = out.parent if str(out.parent) else Path(".")
    if folder.exists() and not folder.is_dir():
        raise ParameterError(
            f"cannot write {out}: {folder} is a file, not a folder; choose another path "
            "(nothing was computed)"
        )
    if not folder.is_dir():
        raise ParameterError(
            f"cannot write {out}: folder {folder} does not exist; create it or choose "
            "another path (nothing was computed)"
        )
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ParameterError(
            f"cannot write {out}: folder {folder} is not writable; choose another path "
            "(nothing was computed)"
        )


def refuse_model_name(out: Path | None, what: str = "a model file is") -> None:
    """Stop before any work when ``-o`` would write a model file (JSON; or ``what``
    else) under another kind's name (``m.csv``: a later reader would take it for a
    table, and ``--force`` would replace the data read)."""
    from blockid.data.files import is_stream

    if out is None or is_stream(out) or out.suffix.lower() in ("", ".json"):
        return
    raise ParameterError(
        f"{out}: {what} JSON, not {out.suffix}; name it {out.with_suffix('.json')}",
        parameter="out",
    )


def refuse_figures(folder: Path | None, names: Sequence[str], force: bool) -> None:
    """Stop before any work when ``--plot DIR`` holds a figure the command would write
    and ``--force`` was not given; refuse a DIR that is a file."""
    if folder is None:
        return
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"{folder} is a file, not a folder; give another --plot DIR")
    if force:
        return
    existing = [folder / n for n in names if (folder / n).exists()]
    if existing:
        shown = ", ".join(str(p) for p in existing)
        raise ParameterError(f"{shown} exist(s); pass --force to replace, or another --plot DIR")


def print_json(doc: Any) -> None:
    """One JSON document on standard output (no markup, no wrapping)."""
    from blockid.data.io import json_text

    sys.stdout.write(json_text(doc))
    sys.stdout.flush()


def metrics_table(title: str, rows: list[tuple[str, dict[str, dict[str, float]]]]) -> Table:
    """A rich table: one row per (label, output), columns MSE .. fit %."""
    table = Table(title=title, title_justify="left")
    for col in ("model", "output", "MSE", "RMSE", "mean |e|", "max |e|", "fit %"):
        left = col in ("model", "output")
        table.add_column(col, justify="left" if left else "right", no_wrap=True)
    for label, metrics in rows:
        for out in metrics["mse"]:
            table.add_row(
                label,
                out,
                f"{metrics['mse'][out]:.4g}",
                f"{metrics['rmse'][out]:.4g}",
                f"{metrics['mae'][out]:.4g}",
                f"{metrics['max_abs_error'][out]:.4g}",
                _fit(metrics["fit_percent"][out]),
            )
    return table


def _fit(value: float | None) -> str:
    """A fit in percent, or "-" where it is undefined (a constant output: NaN, null in
    JSON, and a warning that says so)."""
    return "-" if value is None or value != value else f"{value:.2f}"


#: Parameter tables of more values than this are summarised in one line on the terminal
#: (a polynomial state space has hundreds of monomial coefficients in an arbitrary basis).
MAX_PARAMETER_VALUES = 60


def print_model(model: Any) -> None:
    """The parameters of a model (ARX: one row per coefficient) as a table; a table of
    more than ``MAX_PARAMETER_VALUES`` values as one line saying where they all are."""
    from rich.markup import escape

    rows = model.parameter_table()
    values = sum(len(text.split(",")) for _, text in rows)
    if values > MAX_PARAMETER_VALUES:
        stdout.print(
            f"{model.structure} model: {values} parameter values, not listed here (the model "
            "file, --json and `blockid report` have them all)",
            markup=False,
        )
        return
    table = Table(title=f"{model.structure} model", title_justify="left")
    table.add_column("parameter")
    table.add_column("value", justify="right")
    for name, values in rows:
        table.add_row(escape(name), values)
    stdout.print(table)
