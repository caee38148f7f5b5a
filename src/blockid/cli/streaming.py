"""``blockid stream``: learn a model online from samples piped in as they arrive.

Parses, calls :func:`blockid.workflows.stream.stream_identification` on standard input
and writes its events as JSON lines (:func:`blockid.workflows.stream.json_lines`) on
standard output, one flushed line per event, so that a plant can pipe into it. The
estimator flags are those of ``fit``, generated from the registry.
"""

from __future__ import annotations

import inspect
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import Force, Inputs, Outputs, cli_errors, refuse_to_overwrite, stderr
from blockid.cli._options import (
    DEFAULT_STRUCTURE,
    Structure,
    given,
    structures_help,
    with_fit_options,
)
from blockid.errors import BlockidError

__all__ = ["stream"]

#: This command's flags of the library parameters (for the one-line errors).
_FLAGS = {
    "every": "--every",
    "input_scale": "--input-scale",
    "output_scale": "--output-scale",
    "initial": "--model",
}

StreamMethod = Annotated[
    str | None,
    typer.Option(
        metavar="NAME",
        help="Recursive estimator of the structure (rls, aw-rls, hierarchical-rls, "
        "key-term-rls); default: the structure's first recursive method.",
        show_default=False,
    ),
]
StartModel = Annotated[
    Path | None,
    typer.Option(
        "--model",
        metavar="FILE",
        help="Start from this model file's parameters (theta(0)); its orders apply "
        "where none are given.",
    ),
]
Every = Annotated[
    int,
    typer.Option(
        "--every", metavar="N", min=0, help="Write the parameter estimates every N samples."
    ),
]
FinalModel = Annotated[
    Path | None,
    typer.Option("--out", "-o", metavar="FILE", help="Model file to write at the end of input."),
]
Format = Annotated[
    str,
    typer.Option(
        "--format",
        metavar="csv|jsonl",
        help="Input format: CSV with a header line, or JSON lines (one object per sample).",
    ),
]
Scale = Annotated[
    float | None,
    typer.Option(
        metavar="X",
        help="Expected spread of the signal: the recursion runs on the signal divided by "
        "it (give both scales; default: raw signals).",
        show_default=False,
    ),
]
StopOnError = Annotated[
    bool,
    typer.Option(
        "--stop-on-error",
        help="End at the first unreadable or diverging sample (exit status 1) instead "
        "of reporting it and going on from the last good state.",
    ),
]


@with_fit_options
@cli_errors
def stream(
    inputs: Inputs,
    outputs: Outputs,
    structure: Structure = DEFAULT_STRUCTURE,
    method: StreamMethod = None,
    start: StartModel = None,
    every: Every = 0,
    out: FinalModel = None,
    fmt: Format = "csv",
    input_scale: Scale = None,
    output_scale: Scale = None,
    stop_on_error: StopOnError = False,
    force: Force = False,
    **options: Any,
) -> None:
    """Learn a model sample by sample from standard input (a running plant).

    Reads CSV (a header line, then one sample per line) or JSON lines from standard
    input as the samples arrive and updates a recursive estimator with each. Writes one
    JSON line per sample, {"k": K, "prediction": {..}, "error": {..}} (the one-step
    prediction made before the update; null before the first update), the estimates
    {"k": K, "parameters": {..}} every N samples with --every N, and at the end of input
    {"final": true, "parameters": {..}, "n_samples": N}, with the parameters named as
    in model files. A sample that cannot be read or at which the estimator diverges is
    a line {"k": K, "line": L, "error_message": ".."}; the estimator goes on from its
    last good state (or stops, with --stop-on-error). K counts the data rows from 0.

    The final estimates equal 'blockid fit' of the same record with the same options
    and --passes 1, --no-normalize for the papers' methods and --no-center (online
    learning runs on the raw signals unless --input-scale and --output-scale are given,
    and does not centre them).

    \b
    Example:
      plant | blockid stream -u u -y y --structure hammerstein-wiener \\
          --na 3 --nb 3 --nk 8 --every 1000 -o model.json
    """
    from blockid.errors import EstimationError
    from blockid.models import load_model, save_model
    from blockid.workflows.stream import JsonLines, recursive_method, stream_identification

    refuse_to_overwrite(out, force)
    initial = load_model(start) if start is not None else None
    method = recursive_method(structure, method)
    settings = given(options)
    scales = {"input_scale": input_scale, "output_scale": output_scale}
    events = stream_identification(
        sys.stdin,
        structure,
        inputs,
        outputs,
        method=method,
        options={**settings, **scales},
        initial=initial,
        fmt=fmt,
        every=every,
        stop_on_error=stop_on_error,
    )
    to_line, write, flush = JsonLines(outputs), sys.stdout.write, sys.stdout.flush
    try:
        for event in events:  # the last is the Final
            write(to_line(event) + "\n")
            flush()  # a plant waits for its answer
    except BlockidError as exc:  # options or header: before the first sample
        name = _FLAGS.get(exc.parameter or "")
        if name is None or name in str(exc):
            raise
        raise type(exc)(f"{exc} (option {name})") from None
    if event.stopped:
        raise typer.Exit(code=1)
    if out is None:
        return
    if event.model is None:
        raise EstimationError(f"no model written to {out}: {event.note}")
    settings.update({k: v for k, v in scales.items() if v is not None})
    if start is not None:
        settings["initial"] = str(start)
    record = {"method": method, "settings": settings, "n_samples": event.n_samples}
    save_model(event.model, out, {**record, "online": True}, overwrite=force)
    stderr.print(f"model written to {out}", markup=False)


stream.__doc__ = f"{inspect.cleandoc(stream.__doc__ or '')}\n\n{structures_help()}"
