"""Tables the commands print: a library result's summary (``bla``, ``design``) and the
papers' reproductions (``demo`` and ``reproduce``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from blockid.cli._common import stdout

__all__ = ["print_electrohydraulic", "print_summary"]

#: ``(title, columns, rows, notes)``: the summary a library result gives for a table.
Summary = tuple[str, Sequence[str], Sequence[Sequence[str]], Sequence[str]]


def print_summary(summary: Summary, *, label_column: bool) -> None:
    """A result's summary as a table (numbers right-justified; with ``label_column`` the
    first column, which names the rows, left-justified), then its notes line by line."""
    from rich.table import Table

    title, columns, rows, notes = summary
    table = Table(title=title, title_justify="left")
    for i, column in enumerate(columns):
        table.add_column(column, justify="left" if label_column and i == 0 else "right")
    for row in rows:
        table.add_row(*row)
    stdout.print(table)
    for line in notes:
        stdout.print(line, markup=False)


def print_electrohydraulic(result: Any) -> None:
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
        table.add_column(
            col,
            justify="left" if col in ("model", "estimator") else "right",
            no_wrap=col in ("model", "estimator"),
        )
    notes = [row for row in result.table if "error" in row]
    if notes:
        stdout.print(
            "Each model is fitted by paper B's own estimator (key-term RLS, as published) and "
            "by blockid's default; where the paper's does not converge or diverges on these "
            "data the table says so and the numbered notes below it say why "
            "(docs/convergence.md)."
        )
    for row in result.table:
        best = result.best.get(row["model"], {}).get("estimator") == row["estimator"]
        if "error" in row:
            mark = f"[{notes.index(row) + 1}]"
            table.add_row(row["model"], row["estimator"], f"{_outcome(row['error'])} {mark}",
                          "", "", "")  # fmt: skip
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
    stdout.print(
        "best: * marks the lower MSE of the two estimators of each model. The paper's MSEs "
        "are of its measured rig (other units, noise and trajectory); ours are of blockid's "
        "simulated arm, so compare the ordering and the ratios, not the values."
    )
    if "hammerstein-wiener" in result.best:
        red = result.reductions()
        stdout.print(
            "How much lower the best Hammerstein-Wiener MSE is than each other model's best: "
            + ", ".join(f"{s} {100 * r:.0f} %" for s, r in red.items())
            + " (paper B: hammerstein 13 %, wiener 54 %, arx 58 %)"
        )
    for k, row in enumerate(notes, start=1):
        stdout.print(f"[{k}] {row['model']} {row['estimator']}: {row['error']}", markup=False)


def _outcome(error: str) -> str:
    """What became of a fit that returned no model, in a table cell's words."""
    if "did not converge" in error:
        return "not converged"
    if "diverged" in error:
        return "diverged"
    return "no model"
