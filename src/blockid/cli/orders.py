"""``blockid orders``: the false-nearest-neighbours test paper A chose its orders with.

Parses, calls :func:`blockid.fitting.orders.false_nearest_neighbours`, prints its table
and recommendation (or one JSON document with ``--json``).
"""

from __future__ import annotations

from typing import Annotated, Any

import typer

from blockid.cli._common import cli_errors, flagged, print_json, stdout
from blockid.cli._data import load_data
from blockid.cli._flags import (
    DEFAULT_READING,
    DataPaths,
    Inputs,
    Json,
    Reading,
    reads_data,
    shared,
)
from blockid.errors import ParameterError
from blockid.fitting.order_defaults import DEFAULTS

__all__ = ["orders"]

#: This command's flags of the library parameters (for the one-line errors).
_FLAGS = {name: "--" + name.replace("_", "-") for name in ("max_na", "max_nb", "max_nk")}
_FLAGS.update(threshold="--threshold", noise="--noise", outputs="--output")


def _count(flag: str, what: str) -> Any:
    return typer.Option(flag, metavar="N", help=what)


@reads_data
@cli_errors
def orders(
    data_paths: DataPaths,
    inputs: Inputs,
    outputs: Annotated[
        list[str], shared("outputs", "Output column to test (one; run once per output).")
    ],
    estimation: Annotated[
        str | None,
        shared("estimation", "Samples to use (default: all)."),
    ] = None,
    reading: Reading = DEFAULT_READING,
    max_na: Annotated[int, _count("--max-na", "Output lags tried: 0..N.")] = DEFAULTS["max_na"],
    max_nb: Annotated[int, _count("--max-nb", "Input coefficients tried: 1..N.")] = DEFAULTS[
        "max_nb"
    ],
    max_nk: Annotated[int, _count("--max-nk", "Input delays tried: 0..N.")] = DEFAULTS["max_nk"],
    threshold: Annotated[
        float,
        typer.Option(metavar="PERCENT", help="Pass mark: share of false neighbours."),
    ] = DEFAULTS["threshold"],
    noise: Annotated[
        str,
        typer.Option(
            metavar="FRACTION|auto",
            help="Noise bound, fraction of each signal's spread; auto: estimated from the data.",
        ),
    ] = DEFAULTS["noise"],
    json_out: Json = False,
) -> None:
    """Choose na, nb, nk by false nearest neighbours (the test paper A used).

    Prints the share of false nearest neighbours for every candidate number of output
    lags na and input coefficients nb (at its best delay), the shares over the delay nk
    at the recommended orders, and the recommendation: the smallest na + nb whose share
    is at most the threshold. Several inputs share one nb and one nk.
    """
    level: float | str = noise
    if noise.strip().lower() != "auto":
        try:
            level = float(noise)
        except ValueError:
            raise ParameterError(
                f"--noise must be a fraction of each signal's spread (e.g. 0.01) or auto, "
                f"got {noise!r}",
                parameter="noise",
            ) from None

    if len(outputs) != 1:  # typer once kept the last -y silently
        raise ParameterError(
            f"orders tests one output at a time, got {len(outputs)} ({', '.join(outputs)}); "
            "run it once per output",
            parameter="outputs",
        )
    output = outputs[0]
    data = load_data(data_paths, inputs, [output], reading, estimation)
    from blockid.fitting.orders import false_nearest_neighbours

    with flagged(_FLAGS.get):
        evidence = false_nearest_neighbours(
            data, max_na=max_na, max_nb=max_nb, max_nk=max_nk, threshold=threshold, noise=level
        )
    if json_out:
        print_json(evidence.to_dict())
        return
    _print(evidence)


def _print(ev: Any) -> None:
    from rich.table import Table

    best_delay = ev.percent.argmin(axis=2)
    table = Table(
        title=f"false nearest neighbours, % of {ev.settings['n_scored']} samples: "
        f"{', '.join(ev.inputs)} -> {ev.output} (at the best delay nk)",
        title_justify="left",
    )
    table.add_column("na \\ nb", justify="right")
    for nb in ev.nb:
        table.add_column(f"nb={nb}", justify="right")
    for i, na in enumerate(ev.na):
        cells = [
            f"{ev.percent[i, j, best_delay[i, j]]:.1f} (nk {ev.nk[best_delay[i, j]]})"
            for j in range(len(ev.nb))
        ]
        table.add_row(f"na={na}", *cells)
    stdout.print(table)
    na, nb, nk = ev.recommended
    scan = ", ".join(f"nk={k}: {v:.1f}" for k, v in ev.delay_scan().items())
    stdout.print(f"delay scan at na={na}, nb={nb} (% false): {scan}", markup=False)
    evidence = ev.evidence()
    fewer = ", ".join(f"{k}: {v:.1f} %" for k, v in evidence["one_lag_less"].items())
    stdout.print(
        f"recommended: na={na} nb={nb} nk={nk} ({evidence['percent']:.1f} % false neighbours"
        + (f"; one lag less, {fewer}" if fewer else "")
        + f"; pass mark {ev.pass_mark:.3g} %)",
        markup=False,
    )
    for note in evidence["notes"]:
        stdout.print(f"note: {note}", markup=False)
