"""``blockid design``: an excitation signal for an experiment, its properties, its file.

Parses, checks the whole design before NumPy is imported
(:func:`blockid.design.checks.check_design`), calls :func:`blockid.design.multisine`,
:func:`~blockid.design.prbs` or :func:`~blockid.design.random_binary`, prints the
signal's properties (or one JSON document with ``--json``) and writes it with ``-o`` as
a long table that ``--time-column t --experiment-column realisation`` reads back.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import busy, cli_errors, flagged, print_json, refuse_to_overwrite, stdout
from blockid.cli._flags import Force, Json, Quiet, SamplingTime, shared
from blockid.cli._tables import print_summary
from blockid.design.checks import DEFAULTS, KINDS, check_design, check_positive
from blockid.errors import ParameterError

__all__ = ["design"]

#: The table's columns besides the signal's (``--name``).
COLUMNS = ("t", "realisation", "period")
#: Lines listed one by one in the summary; longer lists show their ends.


def _option(flag: str, metavar: str, help: str) -> Any:
    return typer.Option(flag, metavar=metavar, help=help, show_default=False)


def _default(name: str) -> str:
    value = DEFAULTS[name]
    shown = ",".join(f"{v:g}" for v in value) if isinstance(value, tuple) else f"{value:g}"
    return f" [default: {shown}]"


@cli_errors
def design(
    kind: Annotated[
        str, typer.Argument(metavar="KIND", help=f"One of: {', '.join(KINDS)}.", show_default=False)
    ],
    out: Annotated[
        Path | None,
        shared(
            "out",
            "Table to write (.csv, .tsv or .parquet): columns t, realisation, period and the "
            "signal; read it back with --time-column t --experiment-column realisation.",
        ),
    ] = None,
    fs: Annotated[
        float | None, _option("--fs", "HZ", "Sampling frequency in Hz, or --ts [default: 1].")
    ] = None,
    ts: SamplingTime = None,
    samples: Annotated[
        int | None,
        _option(
            "--samples",
            "N",
            "Samples in one period (multisines, random-binary; required): lines fs/N apart.",
        ),
    ] = None,
    f_min: Annotated[
        float | None,
        _option("--f-min", "HZ", "Lowest frequency excited (multisines) [default: fs/N]."),
    ] = None,
    f_max: Annotated[
        float | None,
        _option(
            "--f-max",
            "HZ",
            "Highest frequency excited (multisines) [default: the Nyquist frequency fs/2, "
            "which itself is never excited].",
        ),
    ] = None,
    group: Annotated[
        int | None,
        _option(
            "--group",
            "N",
            "odd-multisine: one odd line left out at random in each group of N consecutive "
            "odd lines" + _default("group") + ".",
        ),
    ] = None,
    rms: Annotated[
        float | None, _option("--rms", "X", "RMS value (multisines)" + _default("rms") + ".")
    ] = None,
    crest_iterations: Annotated[
        int | None,
        _option(
            "--crest-iterations",
            "N",
            "Multisines: clipping iterations that lower the crest factor, the amplitude "
            "spectrum kept" + _default("crest_iterations") + ": the random phases as drawn.",
        ),
    ] = None,
    order: Annotated[
        int | None,
        _option("--order", "N", "prbs (required): shift-register stages, 2..24; 2^N - 1 bits."),
    ] = None,
    clock: Annotated[
        int | None,
        _option(
            "--clock",
            "N",
            "prbs, random-binary: samples each bit is held (band limit ~0.44 fs/N)"
            + _default("clock")
            + ".",
        ),
    ] = None,
    levels: Annotated[
        str | None,
        _option(
            "--levels",
            "LOW,HIGH",
            "prbs, random-binary: the two values" + _default("levels") + ".",
        ),
    ] = None,
    periods: Annotated[
        int | None,
        shared(
            "periods",
            "Exact repetitions of the period in each realisation" + _default("periods") + ".",
            show_default=False,
        ),
    ] = None,
    realisations: Annotated[
        int | None,
        _option(
            "--realisations",
            "N",
            "Independent realisations, one experiment each (not prbs)"
            + _default("realisations")
            + ".",
        ),
    ] = None,
    seed: Annotated[
        int | None,
        shared(
            "seed",
            "Seed of the phases, the left-out lines or the bits (>= 0)"
            + _default("seed")
            + ": the same seed gives the same signal bit for bit.",
            show_default=False,
        ),
    ] = None,
    name: Annotated[
        str, typer.Option("--name", metavar="NAME", help="Column name of the signal.")
    ] = "u",
    force: Force = False,
    quiet: Quiet = False,
    json_out: Json = False,
) -> None:
    """Design an excitation signal: multisine, odd-multisine, prbs or random-binary.

    Prints each realisation's RMS value, peak and crest factor (for multisines also the
    crest factor of the random phases before optimisation) and the excited lines;
    -o writes the samples. multisine: random phases on every line of the band;
    odd-multisine: odd lines only, one of each group left out, so that a measurement
    shows even and odd nonlinear distortion apart; prbs: a maximum-length sequence;
    random-binary: independent random bits.
    """
    sampling_time = _sampling_time(fs, ts)
    given = {
        "sampling_time": sampling_time,
        "samples": samples,
        "f_min": f_min,
        "f_max": f_max,
        "group": group,
        "rms": rms,
        "crest_iterations": crest_iterations,
        "order": order,
        "clock": clock,
        "levels": levels,
        "periods": periods,
        "realisations": realisations,
        "seed": seed,
    }
    given = {k: v for k, v in given.items() if v is not None}
    _named(check_design, kind, given)
    if name in COLUMNS or not name.strip():
        raise ParameterError(
            f"--name {name!r} would clash with the table's columns {', '.join(COLUMNS)}; "
            "give the signal another name"
        )
    refuse_to_overwrite(out, force)
    if out is not None:
        from blockid.data.files import check_table_target

        check_table_target(out)
    with busy(f"designing the {KINDS[kind]}", quiet or json_out):
        excitation = _named(_make, kind, given)
    if out is not None:
        from blockid.data import write_table

        write_table(excitation.to_frame(name), out, overwrite=force)
    if json_out:
        doc = excitation.to_dict()
        doc["out"] = None if out is None else str(out)
        doc["columns"] = [*COLUMNS, name]
        print_json(doc)
        return
    print_summary(excitation.summary(), label_column=False)
    if out is None:
        stdout.print("no file written (give -o FILE to write the signal)")
    else:
        stdout.print(
            f"written to {out}: columns {', '.join([*COLUMNS, name])} "
            f"(read back with --time-column t --experiment-column realisation)",
            markup=False,
        )


def _sampling_time(fs: float | None, ts: float | None) -> float:
    """The sampling time of ``--fs`` or ``--ts`` (both: they must agree)."""
    if fs is not None:
        fs = _named(check_positive, "fs", fs, " Hz")
    if ts is not None:
        ts = _named(check_positive, "ts", ts, " s")
    if fs is None:
        return DEFAULTS["sampling_time"] if ts is None else ts
    if ts is not None and not math.isclose(ts * fs, 1.0, rel_tol=1e-9):
        raise ParameterError(
            f"--fs {fs:g} and --ts {ts:g} disagree (1/fs = {1 / fs:g} s); give one of them"
        )
    return 1.0 / fs


def _named(fn: Any, *args: Any) -> Any:
    """``fn(*args)``, a library error naming the flag of its parameter."""
    with flagged(_flag):
        return fn(*args)


def _flag(parameter: str) -> str | None:
    """This command's flag of a library parameter (none of ``kind``: the argument)."""
    if parameter == "kind":
        return None
    return "--fs or --ts" if parameter == "sampling_time" else "--" + parameter.replace("_", "-")


def _make(kind: str, given: dict[str, Any]) -> Any:
    """The excitation of ``kind`` with the parameters ``given`` (checked)."""
    from blockid.design import multisine, prbs, random_binary

    if kind == "prbs":
        return prbs(**given)
    if kind == "random-binary":
        return random_binary(**given)
    return multisine(odd=kind == "odd-multisine", **given)
