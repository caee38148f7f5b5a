"""Online identification of a running plant: samples read from a text stream as they come.

:func:`stream_identification` feeds the samples of a text stream (CSV with a header
line, or JSON lines with one object per sample) one at a time to the online learner of
:func:`~blockid.fitting.online.online_estimator` and yields what happened, sample by
sample: the one-step prediction and its error (:class:`Step`), the estimates every
``every`` samples (:class:`Estimates`), a failed sample (:class:`Failure`) and, at the
end of the input, the final estimate (:class:`Final`). Nothing reads ahead: a line is
parsed, learned from and reported before the next is asked for, so a plant's pipe
gets an answer per sample. the :class:`JsonLines` writer gives these events as the JSON lines of
``blockid stream``.

Equivalence. The final estimate is that of the online learner over the samples
learned, which by the contract of :mod:`blockid.fitting.online` is the one-pass
offline fit of the same record with the same options (``passes=1``; the paper methods
with ``normalize=False``, or with ``scales=(input_scale, output_scale)`` when those
are given) — as long as no sample was skipped.

The guard (a robust RLS, :mod:`blockid.workflows.stream_guard`). A sample whose
prediction error is more than ``guard`` (default 10) times the running scale of the
errors, or with a value that far beyond its signal's range, is not learned from, nor
are the samples whose regressors reach back to it; each is a :class:`Step` with
``not_learned`` saying why, and :class:`Final` counts them (``guard``). ``guard=None``
switches the rejection off. Below the threshold a sample is learned as without a
guard, so the equivalence above holds for a clean record.

Failures (a choice). A row that cannot be read (a missing column, text where a number
belongs, NaN) is reported as a :class:`Failure` and skipped: the learner never sees
it. A sample at which the recursion diverges is a :class:`Failure` too, but the
stream recovers: the last good estimate is put back
(:meth:`~blockid.workflows.stream_guard.StreamGuard.diverged`), the sample is taken
into the learner's memory without learning from it, and so are the samples whose
regressors reach back to it; learning goes on after them. With ``stop_on_error`` the
stream ends at the first failure instead. ``k`` counts the data rows of the stream
from 0, skipped ones included, so that it names the row of the user's record; the
learner's own count (``n_samples``) counts the samples taken in (learned from or not).

What a stream cannot vouch for. :class:`Final` carries ``problem`` when its estimate
is not to be trusted: the recursion diverged and did not recover, a signal never
varied (as ``fit`` refuses a constant input), or fewer rows came than the model's
lags and coefficients need (as ``fit`` refuses them, with its message); ``blockid
stream`` then writes no model and exits with status 2. A stream started from a model
(``initial``) is judged on divergence only: that model is its prior.

The model read back at the end has no estimation ranges (``fit`` records them by
simulating the whole record, which a stream does not keep).
"""

from __future__ import annotations

import csv
import itertools
import json
import math
from collections.abc import Iterable, Iterator, Sequence
from typing import Any, NamedTuple

import numpy as np

from blockid.data.dataset import Dataset
from blockid.errors import BlockidError, DataError, EstimationError, ParameterError
from blockid.fitting.online import online_estimator
from blockid.fitting.registry import get_structure
from blockid.workflows.stream_guard import THRESHOLD, StreamGuard

__all__ = [
    "text_lines",
    "FORMATS",
    "Checkpoint",
    "Estimates",
    "Failure",
    "Final",
    "Row",
    "Step",
    "JsonLines",
    "read_samples",
    "recursive_method",
    "stream_identification",
    "StreamSession",
]

#: Text formats of a stream: CSV with a header line, or one JSON object per line.
FORMATS = ("csv", "jsonl")


class Row(NamedTuple):
    """One data row of the stream: its line number (from 1), the input and output values,
    or ``problem`` (why the row cannot be used; the values are then empty)."""

    line: int
    u: tuple[float, ...]
    y: tuple[float, ...]
    problem: str | None = None


class Step(NamedTuple):
    """Sample ``k`` taken in: the one-step prediction made before the update (NaN before
    the first update) and its error ``y - prediction``, one value per output;
    ``not_learned`` says why the learner did not learn from it (the guard), or is None."""

    k: int
    prediction: tuple[float, ...]
    error: tuple[float, ...]
    not_learned: str | None = None


class Estimates(NamedTuple):
    """The estimate after sample ``k``, named as in model files; ``parameters`` is None
    (and ``note`` says why) when no model can be read back yet, ``estimate`` then holds
    the recursion's vector by entry name."""

    k: int
    parameters: dict[str, Any] | None
    estimate: dict[str, float] | None = None
    note: str | None = None


class Failure(NamedTuple):
    """Row ``k`` (line ``line`` of the stream) was skipped: it could not be read, or the
    recursion diverged at it."""

    k: int
    line: int
    message: str


class Final(NamedTuple):
    """The end of the stream: the final estimate (as :class:`Estimates`), the samples
    taken in, the model (None when it cannot be read back), whether the stream
    stopped at a failure, what the guard did
    (:meth:`~blockid.workflows.stream_guard.StreamGuard.summary`) and why the estimate
    is not to be trusted (``problem``, module docstring), or None."""

    n_samples: int
    parameters: dict[str, Any] | None
    model: Any
    stopped: bool = False
    estimate: dict[str, float] | None = None
    note: str | None = None
    guard: dict[str, Any] | None = None
    problem: str | None = None


# ---------------------------------------------------------------------- reading
def _values(texts: list[Any], names: Sequence[str], where: str) -> tuple[tuple, str | None]:
    """The numbers of ``texts`` (the values of ``names``), or why not.

    Finiteness is left to the learner's ``update`` (its :class:`DataError` is reported
    as a failure of the row too)."""
    try:
        return tuple([float(t) for t in texts]), None
    except (TypeError, ValueError):
        pass
    for name, text in zip(names, texts, strict=True):
        try:
            float(text)
        except (TypeError, ValueError):
            return (), f"{where}: {name!r} is {text!r}, not a number"
    raise AssertionError  # pragma: no cover - one of them failed above


#: The delimiters a stream's header line is read with, the first that names the columns.
DELIMITERS = (",", ";", "\t", "|")


def _delimited(lines: Iterable[str], names: Sequence[str]) -> tuple[Iterator[str], str]:
    """The lines again and their delimiter: the first of :data:`DELIMITERS` that splits
    the first non-blank line (the header) into fields naming every column of ``names``
    (as ``fit`` sniffs a file's), else the one splitting it most, else a comma."""
    it = iter(lines)
    skipped: list[str] = []
    for line in it:
        skipped.append(line)
        if line.strip():
            break
    header = skipped[-1] if skipped else ""
    found = ","
    fields = {d: [f.strip().strip('"') for f in header.split(d)] for d in DELIMITERS}
    naming = [d for d in DELIMITERS if all(n in fields[d] for n in names)]
    if naming:
        found = naming[0]
    elif header.strip():
        found = max(DELIMITERS, key=lambda d: (len(fields[d]), -DELIMITERS.index(d)))
    return itertools.chain(skipped, it), found


def _csv_rows(lines: Iterable[str], inputs: Sequence[str], outputs: Sequence[str]) -> Iterator[Row]:
    lines, delimiter = _delimited(lines, [*inputs, *outputs])
    reader = csv.reader(lines, delimiter=delimiter)
    header: list[str] | None = None
    for fields in reader:
        if not fields or (len(fields) == 1 and not fields[0].strip()):
            continue  # blank lines
        if header is None:
            header = [f.strip() for f in fields]
            missing = [n for n in (*inputs, *outputs) if n not in header]
            if missing:
                raise DataError(
                    f"the stream's header line has columns {', '.join(header)}; "
                    f"{', '.join(missing)} missing"
                )
            iu = [header.index(n) for n in inputs]
            iy = [header.index(n) for n in outputs]
            width = len(header)
            continue
        line = reader.line_num
        if len(fields) != width:
            yield Row(line, (), (), f"line {line} has {len(fields)} fields, the header {width}")
            continue
        try:  # the common case first: every field a number
            yield Row(
                line, tuple([float(fields[i]) for i in iu]), tuple([float(fields[i]) for i in iy])
            )
        except ValueError:
            where = f"line {line}"
            _, problem = _values([fields[i] for i in iu], inputs, where)
            if problem is None:
                _, problem = _values([fields[i] for i in iy], outputs, where)
            yield Row(line, (), (), problem)
    if header is None:
        raise DataError("the stream is empty: no header line (CSV needs one naming the columns)")


def _json_rows(
    lines: Iterable[str], inputs: Sequence[str], outputs: Sequence[str]
) -> Iterator[Row]:
    for line, text in enumerate(lines, start=1):
        if not text.strip():
            continue
        where = f"line {line}"
        try:
            record = json.loads(text)
        except json.JSONDecodeError as exc:
            yield Row(line, (), (), f"{where} is not JSON ({exc.msg})")
            continue
        if not isinstance(record, dict):
            yield Row(line, (), (), f"{where} is a JSON {type(record).__name__}, not an object")
            continue
        missing = [n for n in (*inputs, *outputs) if n not in record]
        if missing:
            yield Row(line, (), (), f"{where} has no {', '.join(map(repr, missing))}")
            continue
        u, problem = _values([record[n] for n in inputs], inputs, where)
        y, other = _values([record[n] for n in outputs], outputs, where)
        if problem or other:
            yield Row(line, (), (), problem or other)
        else:
            yield Row(line, u, y)


def text_lines(stream: Any) -> Iterator[str]:
    """The lines of standard input as they come, each decoded as UTF-8 or, where it is
    not, as Windows-1252 (a spreadsheet's Latin-1 export: ``fit`` reads a file so)."""
    raw = getattr(stream, "buffer", None)
    if raw is None:  # already text (a test's stand-in)
        yield from stream
        return
    for line in raw:
        try:
            yield line.decode("utf-8-sig")
        except UnicodeDecodeError:
            yield line.decode("cp1252", errors="replace")


def read_samples(
    lines: Iterable[str], inputs: Sequence[str], outputs: Sequence[str], fmt: str = "csv"
) -> Iterator[Row]:
    """The data rows of a text stream, one :class:`Row` per line, read as they come.

    ``fmt`` is ``"csv"`` (a header line naming the columns, separated by commas,
    semicolons, tabs or bars: the header says which, quoting as the ``csv`` module
    reads it) or ``"jsonl"`` (one object per line; other keys
    are ignored). Blank lines are skipped. A header without the named columns raises
    :class:`~blockid.errors.DataError`; a bad row is a :class:`Row` with ``problem``.

    >>> rows = read_samples(["t,u,y", "0,1.5,2", "1,x,3"], ["u"], ["y"])
    >>> [(r.line, r.u, r.y, r.problem) for r in rows]
    [(2, (1.5,), (2.0,), None), (3, (), (), "line 3: 'u' is 'x', not a number")]
    """
    if fmt not in FORMATS:
        raise ParameterError(f"format {fmt!r} is unknown; use one of {', '.join(FORMATS)}")
    reader = _csv_rows if fmt == "csv" else _json_rows
    return reader(lines, list(inputs), list(outputs))


# ---------------------------------------------------------------------- learning
def recursive_method(structure: str, method: str | None = None) -> str:
    """``method``, or the structure's first recursive method (the one a stream uses
    unless told), from the registry."""
    if method is not None:
        return method
    decl = get_structure(structure)
    for m in decl.methods:
        if m.recursive:
            return m.name
    raise ParameterError(
        f"{structure} has no recursive method ({', '.join(decl.method_names)}): it cannot "
        "learn online",
        parameter="structure",
    )


def _read_back(online: Any) -> tuple[dict[str, Any] | None, Any, dict | None, str | None]:
    try:
        model = online.model()
    except BlockidError as exc:
        return None, None, online.estimate(), " ".join(str(exc).split())
    from blockid.fitting.online import model_parameters

    return model_parameters(model), model, None, None


class Checkpoint(NamedTuple):
    """After row ``k``: what a checkpoint file holds (:meth:`StreamSession.saved`)."""

    k: int
    model: Any
    record: dict[str, Any]


def stream_identification(
    lines: Iterable[str],
    structure: str,
    inputs: Sequence[str],
    outputs: Sequence[str],
    *,
    method: str | None = None,
    options: dict[str, Any] | None = None,
    initial: Any = None,
    fmt: str = "csv",
    every: int = 0,
    stop_on_error: bool = False,
    guard: float | None = THRESHOLD,
) -> Iterator[Step | Estimates | Failure | Final]:
    """Learn ``structure`` online from the samples of a text stream (module docstring).

    Parameters
    ----------
    lines : iterable of str
        The stream (a file object such as ``sys.stdin``, or a list of lines).
    structure, method : str
        As in :func:`~blockid.fitting.fit_model`; the method must be recursive
        (default: the structure's first recursive method, :func:`recursive_method`).
    inputs, outputs : sequence of str
        Columns (CSV) or keys (JSON lines) of the model's signals.
    options : dict
        The method's options (registry; values may be text), plus ``input_scale`` and
        ``output_scale`` (:mod:`blockid.fitting.online`).
    initial : model, optional
        Start from this model's parameters (``theta(0)``).
    fmt : {"csv", "jsonl"}
        The stream's format.
    every : int
        Yield :class:`Estimates` after every ``every``-th sample learned (0: never).
    stop_on_error : bool
        End the stream at the first :class:`Failure` (the :class:`Final` then has
        ``stopped=True``) instead of skipping the sample.
    guard : float or None
        The outlier guard's threshold (module docstring); None switches rejection off.

    The options are checked before the first line is read: a wrong one raises
    :class:`~blockid.errors.ParameterError` at the first ``next()``.
    :class:`StreamSession` does the same and can also checkpoint and resume.

    Examples
    --------
    >>> lines = ["u,y"] + [f"{u},{0.5 * u}" for u in (1.0, -1.0, 2.0, 0.5)]
    >>> events = list(stream_identification(lines, "arx", ["u"], ["y"],
    ...                                     options={"na": 0, "nb": 1, "nk": 0}))
    >>> [type(e).__name__ for e in events]
    ['Step', 'Step', 'Step', 'Step', 'Final']
    >>> events[-1].n_samples, round(events[-1].parameters["y"]["b"]["u"][0], 6)
    (4, 0.5)
    """
    yield from StreamSession(
        lines, structure, inputs, outputs, method=method, options=options, initial=initial,
        fmt=fmt, every=every, stop_on_error=stop_on_error, guard=guard,
    )  # fmt: skip


class StreamSession:
    """An online learner fed from a stream, which can be saved at any sample and
    resumed exactly (``blockid stream --checkpoint``); iterating over it gives the events.

    Parameters are those of :func:`stream_identification`, and

    checkpoint : int
        Yield a :class:`Checkpoint` after every ``checkpoint``-th sample learned.
    resume : dict, optional
        The ``"learner"`` entry of a checkpoint's estimation record (:meth:`saved`). A
        resumed session rebuilds the learner with the saved structure, method and
        options (given ones must agree), restores its state
        (:meth:`~blockid.fitting.online.OnlineEstimator.restore`) and numbers the rows
        on from the saved count, so that stopping and resuming ends bit for bit where
        one uninterrupted stream ends.
    """

    def __init__(
        self,
        lines: Iterable[str],
        structure: str,
        inputs: Sequence[str],
        outputs: Sequence[str],
        *,
        method: str | None = None,
        options: dict[str, Any] | None = None,
        initial: Any = None,
        fmt: str = "csv",
        every: int = 0,
        stop_on_error: bool = False,
        checkpoint: int = 0,
        resume: dict[str, Any] | None = None,
        guard: float | None = THRESHOLD,
    ) -> None:
        self.lines = lines
        self.fmt, self.every, self.stop_on_error = fmt, every, stop_on_error
        self.checkpoint = checkpoint
        self.threshold = guard  # of the guard, built with the learner
        self.guard: StreamGuard | None = None
        self.spec = (structure, inputs, outputs, method, options, initial, resume)
        self.online: Any = None
        self.rows = 0  # data rows read so far (resumed: on from the saved count)
        self.extra_settings: dict[str, Any] = {}  # recorded in saved() (e.g. the start)

    def _start(self) -> None:
        """Build the learner (on the first ``next()``, as the options are checked)."""
        structure, inputs, outputs, method, options, initial, resume = self.spec
        options = {k: v for k, v in (options or {}).items() if v is not None}
        if resume is not None:
            structure, method, options = _resumed(resume, structure, method, options)
            inputs, outputs = resume["inputs"], resume["outputs"]
        self.structure = structure
        self.method = recursive_method(structure, method)
        self.options = dict(options)
        self.inputs, self.outputs = list(inputs), list(outputs)
        opts = dict(options)
        if initial is not None and resume is None:
            opts["initial"] = initial
        self.online = online_estimator(structure, self.method, opts, inputs, outputs)
        self.initial = initial is not None and resume is None  # judged on divergence only
        if resume is not None:
            self.online.restore(resume["state"])
            self.rows = int(resume["rows"])
        self.guard = StreamGuard(self.online, self.threshold)
        if resume is not None and "guard" in resume:
            self.guard.restore(resume["guard"])

    def resume_hint(self, path: Any) -> str:
        """Where the learner's state was written and how to go on from it."""
        return (
            f"model and learner state after {self.online.n_samples} samples written to "
            f"{path}; resume with --model {path}, sending the header line and then the data "
            f"rows from row {self.rows} on (0-based: {self.rows} rows were read)"
        )

    def saved(self) -> tuple[Any, dict[str, Any]]:
        """The model of the current estimate (None when it cannot be read back yet) and
        the estimation record of its file, with the learner's state under
        ``"learner"``."""
        _, model, _, note = _read_back(self.online)
        record = {
            "method": self.method,
            "settings": {
                **{k: _jsonable(v) for k, v in self.options.items()},
                **self.extra_settings,
            },
            "n_samples": self.online.n_samples,
            "online": True,
            "learner": {
                "structure": self.structure,
                "method": self.method,
                "options": {k: _jsonable(v) for k, v in self.options.items()},
                "inputs": self.inputs,
                "outputs": self.outputs,
                "rows": self.rows,
                "state": self.online.state(),
                "guard": self.guard.state(),
            },
            "guard": self.guard.summary(),
        }
        if note is not None:
            record["note"] = note
        return model, record

    def __iter__(self) -> Iterator[Step | Estimates | Failure | Checkpoint | Final]:
        """The events of :func:`stream_identification`, and a :class:`Checkpoint` after
        every ``checkpoint``-th sample taken in (0: never)."""
        every, checkpoint, stop_on_error = self.every, self.checkpoint, self.stop_on_error
        if every < 0:
            raise ParameterError(f"every must be >= 0, got {every}", parameter="every")
        if checkpoint < 0:
            raise ParameterError(
                f"checkpoint must be >= 0, got {checkpoint}", parameter="checkpoint"
            )
        self._start()
        online, guard = self.online, self.guard
        update, before, after = online.update, guard.before, guard.after
        stopped = False
        for row in read_samples(self.lines, self.inputs, self.outputs, self.fmt):
            k = self.rows
            self.rows += 1
            if row.problem is not None:
                yield Failure(k, row.line, row.problem)
                if stop_on_error:
                    stopped = True
                    break
                continue
            values = row.u + row.y
            # a value that is not finite: the learner refuses it (DataError, below)
            why = before(k, values) if all(map(math.isfinite, values)) else None
            taken = online.n_samples
            failure = None
            try:
                if why is None:
                    pred = update(row.u, row.y).tolist()
                    error = [a - b for a, b in zip(row.y, pred, strict=True)]
                    why = after(k, values, error)
                else:
                    pred = update(row.u, row.y, learn=False).tolist()
                    error = [a - b for a, b in zip(row.y, pred, strict=True)]
            except EstimationError as exc:
                failure = self._recover(k, row, exc, why)
            except DataError as exc:
                failure = " ".join(str(exc).split())
            else:
                yield Step(k, pred, error, why)
            if failure is not None:
                yield Failure(k, row.line, failure)
                if stop_on_error:
                    stopped = True
                    break
            if online.n_samples == taken:
                continue
            if every and online.n_samples % every == 0:
                parameters, _, estimate, note = _read_back(online)
                yield Estimates(k, parameters, estimate, note)
            if checkpoint and online.n_samples % checkpoint == 0:
                yield Checkpoint(k, *self.saved())
        parameters, model, estimate, note = _read_back(online)
        yield Final(
            online.n_samples, parameters, model, stopped, estimate, note, guard.summary(),
            self._problem(),
        )  # fmt: skip

    def _recover(self, k: int, row: Row, exc: EstimationError, why: str | None) -> str:
        """The message of row ``k`` whose update raised. A learned row diverged: the
        last good estimate back, the row taken in without learning (skipped when the
        learner cannot take it in). A held row the learner cannot take in: skipped."""
        summary = getattr(exc, "summary", None) or " ".join(str(exc).split())
        if self.stop_on_error:  # the stream ends here: the learner as it was
            return " ".join(str(exc).split())
        if why is not None:
            return f"{summary}. This row was not to be learned from ({why}); it is skipped"
        message = self.guard.diverged(k, summary)
        try:
            self.online.update(row.u, row.y, learn=False)
        except EstimationError:
            message += " (this row itself could not be taken in: it is skipped)"
        return message

    def _problem(self) -> str | None:
        """Why the final estimate is not to be trusted (module docstring), or None."""
        online, guard = self.online, self.guard
        unrecovered = guard.unrecovered()
        if unrecovered is not None or self.initial:
            return unrecovered
        if online.n_samples == 0:
            return "no sample was learned (every row was refused; the lines on stdout say why)"
        lag, n, rows = online.max_lag, online.n_parameters, online.n_samples
        if rows <= lag or rows - lag < n:  # fit's check, with its message
            shape = (rows, len(self.inputs)), (rows, len(self.outputs))
            data = Dataset.from_arrays(
                *(np.zeros(s) for s in shape), self.inputs, self.outputs, name="the stream"
            )
            orders = ", ".join(f"{k}={self.options[k]}" for k in _ORDERS if k in self.options)
            what = f"{self.structure} with {orders}" if orders else self.structure
            try:
                data.check_orders(lag, n, what=what)
            except BlockidError as exc:
                return str(exc).replace("use a longer range", "stream more rows")
        return guard.constant()


#: Options that set a model's orders (named in the message of too few rows).
_ORDERS = ("na", "nb", "nk", "r1", "r2")


def _jsonable(value: Any) -> Any:
    return value if isinstance(value, str | int | float | bool) or value is None else str(value)


def _resumed(
    resume: dict[str, Any], structure: str, method: str | None, options: dict[str, Any]
) -> tuple[str, str | None, dict[str, Any]]:
    """The saved structure, method and options, checked against those given."""
    saved_options = dict(resume.get("options", {}))
    if structure != resume["structure"]:
        raise ParameterError(
            f"the checkpoint was learned as {resume['structure']}, not {structure}: give "
            f"--structure {resume['structure']} (or leave it out) to resume it",
            parameter="structure",
        )
    if method is not None and method != resume["method"]:
        raise ParameterError(
            f"the checkpoint was learned by {resume['method']}, not {method}",
            parameter="method",
        )
    differ = [k for k, v in options.items() if str(saved_options.get(k)) != str(v)]
    if differ:
        shown = ", ".join(f"{k}={saved_options.get(k)!r}" for k in differ)
        raise ParameterError(
            f"the checkpoint was learned with {shown}; resume it with the same options "
            "(or none: they are read from the file)",
            parameter=differ[0],
        )
    return resume["structure"], resume["method"], saved_options


# ---------------------------------------------------------------------- writing
def _value(x: float) -> str:
    return repr(x) if math.isfinite(x) else "null"  # repr: what json.dumps writes


def _dumps(doc: Any) -> str:
    return json.dumps(doc, allow_nan=False)


class JsonLines:
    """The JSON line (without newline) of an event, as ``blockid stream`` writes them.

    ``{"k": 3, "prediction": {"y": 0.1}, "error": {"y": -0.02}}`` per sample (``null``
    before the first update), with ``"not_learned": ".."`` (why) when the guard kept
    the learner from learning from it; ``{"k": .., "parameters": {..}}`` every
    ``every`` samples; ``{"k": .., "line": .., "error_message": ".."}`` for a skipped
    or diverging row; and ``{"final": true, "parameters": {..}, "n_samples": ..,
    "guard": {..}}`` at the end (``"stopped": true`` when it stopped at a failure,
    ``"problem": ".."`` when the estimate is not to be trusted). The per-sample line is
    written without :func:`json.dumps` (the same text, a few microseconds less).

    >>> line = JsonLines(["y"])
    >>> line(Step(0, [float("nan")], [float("nan")]))
    '{"k": 0, "prediction": {"y": null}, "error": {"y": null}}'
    >>> line(Step(1, [0.5], [0.25]))
    '{"k": 1, "prediction": {"y": 0.5}, "error": {"y": 0.25}}'
    >>> line(Step(2, [0.5], [9.5], "outlier"))
    '{"k": 2, "prediction": {"y": 0.5}, "error": {"y": 9.5}, "not_learned": "outlier"}'
    """

    def __init__(self, outputs: Sequence[str]) -> None:
        self.keys = [_dumps(name) for name in outputs]  # output names, quoted once

    def __call__(self, event: Step | Estimates | Failure | Final) -> str:
        if type(event) is Step:  # the per-sample path
            keys = self.keys
            if len(keys) == 1 and event.not_learned is None:
                q, p, e = keys[0], event.prediction[0], event.error[0]
                p = repr(p) if p - p == 0.0 else "null"  # _value inlined: finite or null
                e = repr(e) if e - e == 0.0 else "null"
                return f'{{"k": {event.k}, "prediction": {{{q}: {p}}}, "error": {{{q}: {e}}}}}'
            p = ", ".join(f"{q}: {_value(v)}" for q, v in zip(keys, event.prediction, strict=True))
            e = ", ".join(f"{q}: {_value(v)}" for q, v in zip(keys, event.error, strict=True))
            why = event.not_learned
            why = "" if why is None else f', "not_learned": {_dumps(why)}'
            return f'{{"k": {event.k}, "prediction": {{{p}}}, "error": {{{e}}}{why}}}'
        if isinstance(event, Estimates):
            return _dumps(_with_note({"k": event.k, "parameters": event.parameters}, event))
        if isinstance(event, Failure):
            return _dumps({"k": event.k, "line": event.line, "error_message": event.message})
        doc = {"final": True, "parameters": event.parameters, "n_samples": event.n_samples}
        if event.stopped:
            doc["stopped"] = True
        doc["guard"] = event.guard
        if event.problem is not None:
            doc["problem"] = event.problem
        return _dumps(_with_note(doc, event))


def _with_note(doc: dict[str, Any], event: Estimates | Final) -> dict[str, Any]:
    if event.note is not None:
        doc["estimate"] = event.estimate
        doc["note"] = event.note
    return doc
