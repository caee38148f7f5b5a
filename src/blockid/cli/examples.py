"""``blockid demo``, ``reproduce windtunnel|electrohydraulic`` and ``example-data``.

The runs are library workflows (:mod:`blockid.workflows`); these commands print them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import busy, cli_errors, print_json, refuse_to_overwrite, stdout
from blockid.cli._data import check_arguments
from blockid.cli._flags import FolderForce, Force, Json, Quiet, Seed, shared
from blockid.cli._tables import print_electrohydraulic as _print_electrohydraulic
from blockid.workflows.examples import EXAMPLES, check_example

__all__ = ["demo", "example_data", "reproduce_app"]

reproduce_app = typer.Typer(
    help="Reproduce the seed papers' experiments on blockid's simulated plants.",
    no_args_is_help=True,
    rich_markup_mode=None,
)

FiguresDir = Annotated[
    Path | None,
    shared("plot", "Folder for the PNG figures.", show_default=False),
]
#: ``--figures``, the flag's old name, kept (hidden) so that scripts do not break.
OldFiguresDir = Annotated[Path | None, typer.Option("--figures", hidden=True)]
#: What the spinner says while the papers' experiments run (demo and reproduce).
_ELECTROHYDRAULIC = "paper B's experiment: simulating the arm, fitting 4 structures 2 ways"
_WINDTUNNEL = "paper A's experiment: simulating the tunnel, fitting the networks"


def _folder(new: Path | None, old: Path | None, default: str, force: bool) -> Path:
    """The output folder of ``--plot`` (or its hidden old name), refused when it holds
    files and ``--force`` was not given: the run would replace them, as ``fit -o`` does
    only with ``--force``."""
    from blockid.errors import ParameterError

    folder = new if new is not None else old if old is not None else Path(default)
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"{folder} is a file, not a folder; give another --plot DIR")
    if folder.is_dir() and any(folder.iterdir()) and not force:
        raise ParameterError(
            f"{folder} exists and is not empty; pass --force to replace its files, or give "
            "another --plot DIR"
        )
    return folder


@cli_errors
def demo(
    plot: Annotated[
        Path | None,
        shared(
            "plot",
            "Folder for the data, models and figures [default: demo-output].",
            show_default=False,
        ),
    ] = None,
    output_dir: Annotated[Path | None, typer.Option("--output-dir", hidden=True)] = None,
    seed: Seed = 0,
    force: FolderForce = False,
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Run the built-in example: paper B's experiment on the simulated excavator arm.

    Same as 'blockid reproduce electrohydraulic', and keeps the data, the best model of
    every structure and the figures in the output folder.
    """
    from blockid.workflows.demo import run_demo

    output_dir = _folder(plot, output_dir, "demo-output", force)
    with busy(_ELECTROHYDRAULIC, quiet or json_out):
        result = run_demo(output_dir, seed=seed)
    if json_out:
        print_json(result.to_dict())
        return
    _print_electrohydraulic(result)
    stdout.print(f"data, models, figures and results.json written to {output_dir}/")


@reproduce_app.command("windtunnel")
@cli_errors
def reproduce_windtunnel(
    seed: Seed = 0,
    plot: FiguresDir = None,
    figures: OldFiguresDir = None,
    force: FolderForce = False,
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Paper A: block-oriented network vs conventional linear model (Table 2).

    Figures go to --plot DIR (default: reproduce-windtunnel).
    """
    from blockid.workflows.reproduce_windtunnel import PAPER_TABLE, reproduce_windtunnel

    figures = _folder(plot, figures, "reproduce-windtunnel", force)
    with busy(_WINDTUNNEL, quiet or json_out):
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
        table.add_row(row["condition"], row["model"], row["estimator"], *_errors(row))
    for row in PAPER_TABLE:
        table.add_row(row["condition"], row["model"], "paper A (measured data)", *_errors(row))
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
        for est, p in [("truth", result.truth[condition]), *by_est.items()]:
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


def _errors(row: dict[str, Any]) -> tuple[str, ...]:
    """RMSE and maximum absolute error of P0 (y1) and Ma (y2), as paper A prints them."""
    rmse, worst = row["rmse"], row["max_abs_error"]
    return (f"{rmse['y1']:.4f}", f"{rmse['y2']:.5f}", f"{worst['y1']:.4f}", f"{worst['y2']:.5f}")


@reproduce_app.command("electrohydraulic")
@cli_errors
def reproduce_electrohydraulic(
    seed: Seed = 0,
    plot: FiguresDir = None,
    figures: OldFiguresDir = None,
    force: FolderForce = False,
    validation_bandwidth: Annotated[
        str,
        typer.Option(
            metavar="HZ|none",
            help="Corner frequency [Hz] of the validation command's low-pass, below 10; "
            "'none' for the step-like moves that ask the models to extrapolate in frequency.",
        ),
    ] = "0.5",
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Paper B: Hammerstein-Wiener vs Hammerstein, Wiener and ARX (Table 2).

    Figures go to --plot DIR (default: reproduce-electrohydraulic).
    """
    from blockid.workflows.reproduce_electrohydraulic import reproduce_electrohydraulic

    figures = _folder(plot, figures, "reproduce-electrohydraulic", force)
    bandwidth = _bandwidth(validation_bandwidth)
    with busy(_ELECTROHYDRAULIC, quiet or json_out):
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


@cli_errors
def example_data(
    name: Annotated[str, typer.Argument(metavar="NAME", help=f"One of: {', '.join(EXAMPLES)}.")],
    out: Annotated[Path, shared("out", "File to write (.csv/.parquet).")],
    seed: Seed = 0,
    force: Force = False,
) -> None:
    """Write a record of a built-in simulated plant, to try the other commands on.

    One continuous record: the estimation experiment followed by the validation
    experiment (the ranges to use are printed). electrohydraulic: columns t, current,
    velocity (estimation: the averaged multisine runs; validation: a general trajectory).
    windtunnel-*: t, u1, u2, v1, v2, y1, y2 at that operating condition.
    """
    check_example(name)
    refuse_to_overwrite(out, force)
    check_arguments(table=out)
    from blockid.data import write_table
    from blockid.workflows.examples import example_record

    record = example_record(name, seed=seed)
    write_table(record.frame, out, overwrite=force)
    (a, b), (c, d) = record.estimation, record.validation
    stdout.print(
        f"{name} (seed {seed}) written to {out}: estimation record {a}:{b}, "
        f"validation record {c}:{d} (use with --estimation/--validation)"
    )
