"""``blockid stream``: learn a model online from samples piped in as they arrive.

Parses, calls :func:`blockid.workflows.stream.stream_identification` on standard input
and writes its events as JSON lines (:func:`blockid.workflows.stream.json_lines`) on
standard output, one flushed line per event, so that a plant can pipe into it. The
estimator flags are those of ``fit``, generated from the registry.
"""

from __future__ import annotations

import inspect
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from blockid.cli._common import cli_errors, flagged, refuse_to_overwrite, stderr
from blockid.cli._data import check_arguments
from blockid.cli._flags import Force, Inputs, Outputs, shared
from blockid.cli._options import (
    DEFAULT_STRUCTURE,
    given,
    structures_help,
    with_fit_options,
)
from blockid.workflows.stream_guard import THRESHOLD

__all__ = ["stream"]


#: This command's flags of the library parameters (for the one-line errors).
_FLAGS = {
    "every": "--every",
    "input_scale": "--input-scale",
    "output_scale": "--output-scale",
    "initial": "--model",
    "guard": "--outlier-threshold",
}

StreamMethod = Annotated[
    str | None,
    shared(
        "method",
        "Recursive estimator of the structure (rls, aw-rls, hierarchical-rls, "
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
        "where none are given. A file written by stream (-o, --checkpoint) resumes "
        "exactly where it stopped.",
    ),
]
CheckpointEvery = Annotated[
    int,
    typer.Option(
        "--checkpoint",
        metavar="N",
        min=0,
        help="Write the model and the learner's state to -o FILE (atomically) every N "
        "samples; it is also written on Ctrl-C or SIGTERM. --model FILE resumes it.",
    ),
]
StreamStructure = Annotated[
    str | None,
    shared(
        "structure",
        "Model structure (default arx, or the resumed file's; see below).",
        show_default=False,
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
    shared("out", "Model file to write at the end of input (and at checkpoints, and on Ctrl-C)."),
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
Guard = Annotated[
    bool,
    typer.Option(
        "--guard/--no-guard",
        help="Do not learn from a sample whose prediction error is many times the running "
        "error scale, or with a value far beyond its signal's range, nor from the samples "
        "whose regressors reach back to it (a glitch of a live plant). --no-guard learns "
        "from every sample.",
    ),
]
OutlierThreshold = Annotated[
    float,
    typer.Option(
        "--outlier-threshold",
        metavar="T",
        help="The guard's threshold: a multiple of the running error scale, and of a "
        "signal's range width beyond its range.",
    ),
]


@with_fit_options
@cli_errors
def stream(
    inputs: Inputs,
    outputs: Outputs,
    structure: StreamStructure = None,
    method: StreamMethod = None,
    start: StartModel = None,
    every: Every = 0,
    checkpoint: CheckpointEvery = 0,
    out: FinalModel = None,
    fmt: Format = "csv",
    input_scale: Scale = None,
    output_scale: Scale = None,
    stop_on_error: StopOnError = False,
    guard: Guard = True,
    outlier_threshold: OutlierThreshold = THRESHOLD,
    force: Force = False,
    **options: Any,
) -> None:
    """Learn a model sample by sample from standard input (a running plant).

    Reads CSV (a header line, then one sample per line) or JSON lines from standard
    input as the samples arrive and updates a recursive estimator with each. Writes one
    JSON line per sample, {"k": K, "prediction": {..}, "error": {..}} (the one-step
    prediction made before the update; null before the first update), the estimates
    {"k": K, "parameters": {..}} every N samples with --every N, and at the end of input
    {"final": true, "parameters": {..}, "n_samples": N, "guard": {..}}, with the
    parameters named as in model files. A sample the guard kept the estimator from
    learning from has "not_learned": "why" in its line, and the final "guard" counts
    them. A sample that cannot be read or at which the estimator diverges is a line
    {"k": K, "line": L, "error_message": ".."}; the estimator goes on from its last good
    estimate (or stops, with --stop-on-error). K counts the data rows from 0. An
    estimate that diverged and did not recover, or that saw a constant signal or too
    few rows, is not written: exit status 2, and "problem" in the final line says why.

    The final estimates equal 'blockid fit' of the same record with the same options
    and --passes 1, --no-normalize for the papers' methods and --no-center (online
    learning runs on the raw signals unless --input-scale and --output-scale are given,
    and does not centre them).

    \b
    Example:
      plant | blockid stream -u u -y y --structure hammerstein-wiener \\
          --na 3 --nb 3 --nk 8 --every 1000 -o model.json
    """
    import json
    import signal

    from blockid.errors import EstimationError, ParameterError
    from blockid.fitting.registry import get_structure

    if checkpoint and out is None:
        raise ParameterError("--checkpoint N writes to -o FILE: give one", parameter="out")
    for name, scale in (("--input-scale", input_scale), ("--output-scale", output_scale)):
        if scale is not None and not 0.0 < scale < float("inf"):
            raise ParameterError(
                f"{name} must be a positive number (the signal's expected spread), got {scale:g}"
            )
    refuse_to_overwrite(out, force)
    check_arguments(model=start)
    if structure is not None:
        get_structure(structure)
    from blockid.models import load_model, save_model
    from blockid.workflows.stream import (
        Checkpoint,
        JsonLines,
        StreamSession,
        recursive_method,
        text_lines,
    )

    resume, initial = None, None
    if start is not None:
        initial = load_model(start)
        learner = json.loads(start.read_text()).get("estimation", {}).get("learner")
        if learner is not None:
            resume, initial = learner, None
            structure = structure or learner["structure"]
    structure = structure or DEFAULT_STRUCTURE
    method = method or (resume["method"] if resume else recursive_method(structure, method))
    settings = given(options)
    scales = {"input_scale": input_scale, "output_scale": output_scale}
    session = StreamSession(
        text_lines(sys.stdin), structure, inputs, outputs, method=method,
        options={**settings, **{k: v for k, v in scales.items() if v is not None}},
        initial=initial, fmt=fmt, every=every, stop_on_error=stop_on_error,
        checkpoint=checkpoint, resume=resume, guard=outlier_threshold if guard else None,
    )  # fmt: skip
    events = iter(session)
    to_line, write, flush = JsonLines(outputs), sys.stdout.write, sys.stdout.flush
    if start is not None and resume is None:
        session.extra_settings["initial"] = str(start)

    def save(model: Any, record: dict[str, Any]) -> bool:
        if out is None or model is None:
            return False
        save_model(model, out, record, overwrite=True)  # our own file after the first
        return True

    def stop(number: int, frame: Any) -> None:
        raise _Stopped(number)

    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    event: Any = None
    try:
        with flagged(_FLAGS.get):  # options or header: errors before the first sample
            for event in events:  # the last is the Final
                if isinstance(event, Checkpoint):
                    save(event.model, event.record)
                    continue
                try:
                    write(to_line(event) + "\n")
                    flush()  # a plant waits for its answer
                except BrokenPipeError:  # the reader closed stdout: stop as on SIGPIPE, saving
                    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
                    raise _Stopped(signal.SIGPIPE) from None
    except _Stopped as exc:
        name = signal.Signals(exc.number).name
        written = session.online is not None and save(*session.saved())
        where = (
            session.resume_hint(out) if written else "nothing written (no -o FILE, or no model yet)"
        )
        stderr.print(f"stopped by {name}: {where}", markup=False)
        raise typer.Exit(code=128 + exc.number) from None
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    from blockid.workflows.stream_guard import guard_note

    note = guard_note(event.guard)
    if note is not None:
        stderr.print(note, markup=False)
    if event.stopped:
        raise typer.Exit(code=1)
    problem = event.problem
    if out is None:
        if problem is not None:
            raise EstimationError(problem)
        return
    if problem is None and event.n_samples == 0:
        problem = "no sample was learned (every row was refused; the lines on stdout say why)"
    if problem is None and event.model is None:
        problem = event.note
    if problem is not None:
        raise EstimationError(f"no model written to {out}: {problem}")
    save(*session.saved())
    stderr.print(f"model written to {out}", markup=False)


class _Stopped(Exception):
    """SIGINT or SIGTERM arrived during the stream, or its stdout was closed (SIGPIPE)."""

    def __init__(self, number: int) -> None:
        super().__init__(number)
        self.number = number


stream.__doc__ = f"{inspect.cleandoc(stream.__doc__ or '')}\n\n{structures_help()}"
