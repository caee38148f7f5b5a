"""Tables of the papers' reproductions, printed by ``demo`` and ``reproduce``."""

from __future__ import annotations

from typing import Any

from blockid.cli._common import stdout

__all__ = ["print_electrohydraulic"]


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
    for row in result.table:
        if "error" in row:
            stdout.print(f"{row['model']} {row['estimator']}: {row['error']}", markup=False)
