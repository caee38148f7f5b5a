"""The commands' data files and argument checks, before the numerical stack is imported.

:func:`check_arguments` refuses bad files, ranges, structures and options with one line
while only the standard library is loaded; :func:`load_data` reads the files once they
pass (``tests/cli/test_startup.py`` checks both).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from blockid.cli._flags import Reading

__all__ = [
    "check_arguments",
    "data_label",
    "load_data",
    "load_model_data",
    "model_rate",
    "select_range",
]


def check_arguments(
    paths: Sequence[Path] | None = None,
    *,
    structure: str | None = None,
    method: str | None = None,
    options: dict[str, Any] | None = None,
    ranges: dict[str, str | None] | None = None,
    model: Path | None = None,
    table: Path | None = None,
) -> None:
    """Refuse bad arguments before the numerical stack is imported: missing, empty or
    unknown data files, malformed sample ranges (``{flag: text}``), an unknown
    structure or method, options the method does not take or values out of range
    (block and forgetting values are checked by the fit), a ``model`` file that is not
    one, a ``table`` to write of an unknown type."""
    from blockid.data.files import check_data_paths, check_table_target, read_model_document
    from blockid.data.ranges import parse_range
    from blockid.fitting.registry import resolve_options

    if model is not None:
        read_model_document(model)
    if paths is not None:
        check_data_paths(paths)
    if table is not None:
        check_table_target(table)
    for what, text in (ranges or {}).items():
        if text:
            parse_range(text, what)
    if structure is not None:
        resolve_options(structure, method, options or {}, light=True)


def load_data(
    paths: Sequence[Path],
    inputs: Sequence[str],
    outputs: Sequence[str],
    reading: Reading,
    rng: str | None = None,
    what: str = "--estimation",
) -> Any:
    """Read the data files as ``reading`` says (``--ts``, ``--time-column``,
    ``--experiment-column``); keep the samples of ``rng`` (the text of flag ``what``).

    The paths and the range are checked before pandas is imported
    (:func:`check_arguments`)."""
    check_arguments(paths, ranges={what: rng})
    from blockid.data import read_data

    data = read_data(
        paths,
        inputs,
        outputs,
        sampling_time=reading.ts,
        time_column=reading.time_column,
        experiment_column=reading.experiment_column,
    )
    return select_range(data, rng, what)


def load_model_data(
    model_path: Path, paths: Sequence[Path], reading: Reading, rng: str | None
) -> tuple[Any, Any]:
    """The model of ``model_path`` and the samples of ``--range`` ``rng`` of the data
    files, read with the model's signals at its rate (:func:`model_rate`)."""
    from blockid.models import load_model

    model = load_model(model_path)
    rate = model_rate(model, reading.ts, model_path)  # --ts 0 is refused, not dropped
    inputs, outputs = list(model.inputs), list(model.outputs)
    data = load_data(paths, inputs, outputs, reading._replace(ts=rate), rng, "--range")
    return model, data


def select_range(data: Any, rng: str | None, what: str) -> Any:
    """The samples of ``data`` in range ``rng`` (the text of flag ``what``; None: all)."""
    from blockid.data.ranges import parse_range

    if not rng:
        return data
    start, stop = parse_range(rng, what)
    return data.select(start, stop, what=what)


def data_label(paths: Sequence[Path], rng: str | None) -> str:
    """The data files and range read, as titles and figures name them: ``a.csv [0:500]``."""
    return ", ".join(map(str, paths)) + (f" [{rng}]" if rng else "")


def model_rate(model: Any, ts: float | None, model_path: Path) -> float | None:
    """The sampling time to read data at for ``model``: ``--ts`` or the model's own; a
    ``--ts`` other than a model's sampling time is refused (the model runs at the rate
    it was fitted at, and would be scored at another without a word)."""
    import math

    from blockid.errors import ParameterError

    if ts is None or not model.sampling_time:
        return ts if ts is not None else model.sampling_time
    if not math.isclose(ts, model.sampling_time):
        raise ParameterError(
            f"--ts {ts:g} differs from the sampling time of {model_path}, "
            f"{model.sampling_time:g} s: the model runs at the rate it was fitted at; resample "
            "the data to it, or leave --ts out"
        )
    return ts
