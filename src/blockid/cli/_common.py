"""Helpers shared by the CLI commands: option parsing, error reporting, output."""

from __future__ import annotations

import functools
import json
import sys
from collections.abc import Callable
from typing import Any

import typer
from rich.console import Console
from rich.table import Table

from blockid.errors import BlockidError, OrderError

__all__ = ["stdout", "stderr", "cli_errors", "parse_order", "print_json", "metrics_table"]

# rich falls back to 80 columns when writing to a pipe or file, which truncates numbers
# in tables; use a wide console there (a terminal keeps its own width).
stdout = Console(highlight=False, soft_wrap=True, width=None if sys.stdout.isatty() else 160)
stderr = Console(
    stderr=True, highlight=False, soft_wrap=True, width=None if sys.stderr.isatty() else 400
)


def cli_errors(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Turn blockid errors into one readable line on stderr and exit status 2."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except BlockidError as exc:
            stderr.print(f"[bold red]error:[/] {exc}", soft_wrap=True, markup=True)
            raise typer.Exit(code=2) from None
        except KeyboardInterrupt:
            stderr.print("interrupted; no output file was written")
            raise typer.Exit(code=130) from None

    return wrapper


def parse_order(text: str | None, name: str) -> Any:
    """``"2"`` -> 2; ``"2,1;1,2"`` -> [[2, 1], [1, 2]] (rows: outputs)."""
    if text is None:
        return None
    try:
        rows = [[int(v) for v in row.replace(" ", ",").split(",") if v] for row in text.split(";")]
    except ValueError:
        raise OrderError(
            f"--{name} {text!r}: give a whole number, or a matrix with rows separated by ';' "
            "and entries by ',' (rows: outputs), e.g. --na 2 or --na '2,1;1,2'"
        ) from None
    if len(rows) == 1 and len(rows[0]) == 1:
        return rows[0][0]
    return rows


def print_json(doc: Any) -> None:
    """One JSON document on standard output (no markup, no wrapping)."""
    sys.stdout.write(json.dumps(doc, indent=2, allow_nan=False) + "\n")
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
                f"{metrics['fit_percent'][out]:.2f}",
            )
    return table
