"""Reading input/output records from files and writing tables and text atomically.

Supported data files (chosen by suffix):

- ``.csv``, ``.tsv``, ``.txt``: delimited text with a header line. The delimiter
  (comma, tab, semicolon or bar) is sniffed from the first lines; a ``.txt``/``.tsv`` file
  with none of them is read as whitespace-separated.
- ``.parquet``: read with pyarrow.
- ``.mat``: MATLAB v4/v5/v7 files (not v7.3). Each signal is a variable: a vector is one
  experiment, an N x E matrix holds E experiments, one per column.

Every error names the file; errors in a cell also name the column, the data row
(1-based) and, for text files, the line of the file.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import secrets
import warnings
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np
import pandas as pd

from blockid.data.dataset import (
    Dataset,
    Locator,
    _check_sampling_time,
    _check_signal_names,
    _concat,
    _frame_to_dataset,
    _time_like,
    _unknown_name_message,
    _Where,
)
from blockid.data.files import (
    READ_SUFFIXES,
    WRITE_SUFFIXES,
    check_data_paths,
    check_file,
    check_suffix,
    check_table_target,
    is_stream,
)
from blockid.errors import DataError

__all__ = [
    "is_stream",
    "READ_SUFFIXES",
    "json_safe",
    "json_text",
    "WRITE_SUFFIXES",
    "read_data",
    "write_table",
    "write_text_atomic",
]

_TEXT_SUFFIXES = (".csv", ".tsv", ".txt")
_WHITESPACE = r"\s+"
_SNIFF_BYTES = 64 * 1024
#: Delimiters tried, most likely first, for each text suffix.
_DELIMITERS = {".csv": ",;\t|", ".tsv": "\t,;|", ".txt": "\t,;|"}

PathLike = str | os.PathLike


# ---------------------------------------------------------------------- reading
def read_data(
    paths: PathLike | Sequence[PathLike],
    inputs: Sequence[str],
    outputs: Sequence[str],
    sampling_time: float | None = None,
    time_column: str | None = None,
    experiment_column: str | None = None,
) -> Dataset:
    """Read input/output data from one or more files.

    Parameters
    ----------
    paths : path or sequence of paths
        Data files (``.csv``, ``.tsv``, ``.txt``, ``.parquet``, ``.mat``). Each file gives
        one or more experiments.
    inputs, outputs : sequence of str
        Column (or .mat variable) names of the input and output signals.
    sampling_time : float, optional
        Sampling period; checked against ``time_column`` if both are given.
    time_column : str, optional
        Column of sample times, from which the sampling time is inferred (median step;
        steps must stay within 1 % of it).
    experiment_column : str, optional
        Column that labels the experiment of each row (rows of one experiment contiguous).

    Returns
    -------
    Dataset
        Experiments are named after the file stem (``run1`` for ``data/run1.csv``), the
        experiment-column value (one file) or ``stem/value`` (several files), and
        ``stem column j`` for column j (1-based) of a .mat matrix. All files must share
        one sampling time.

    Raises
    ------
    DataError
        For a missing, empty, unreadable or malformed file; the message names the file,
        and for a bad cell the column, data row, file line and value.
    """
    inputs, outputs = _check_signal_names(inputs, outputs)
    sampling_time = _check_sampling_time(sampling_time)
    path_list = [paths] if isinstance(paths, str | os.PathLike) else list(paths)
    if not path_list:
        raise DataError("no data file given; name at least one .csv, .parquet or .mat file")
    shown = check_data_paths(path_list)
    stems = [Path(p).stem for p in shown]
    names = [
        stem if stems.count(stem) == 1 else text for stem, text in zip(stems, shown, strict=True)
    ]
    several = len(path_list) > 1
    options = dict(
        inputs=inputs,
        outputs=outputs,
        sampling_time=sampling_time,
        time_column=time_column,
        experiment_column=experiment_column,
    )
    datasets = [
        _read_one(Path(text), text, name, several, **options)
        for text, name in zip(shown, names, strict=True)
    ]
    if not several:
        return datasets[0]
    return _concat(datasets, source=", ".join(shown))


def _read_one(path: Path, shown: str, name: str, several: bool, **options: Any) -> Dataset:
    suffix = check_suffix(path)
    check_file(path, shown)
    try:
        if suffix == ".mat":
            return _read_mat(path, shown, name, several, **options)
        if suffix == ".parquet":
            frame, where, empty = _read_parquet(path, shown, options)
        else:
            frame, where, empty = _read_text(path, shown, suffix, options)
    except PermissionError:
        raise DataError(f"{shown} cannot be read: permission denied") from None
    return _frame_to_dataset(
        frame,
        source=shown,
        name=name,
        split_prefix=name if several else None,
        where=where,
        empty_message=empty,
        **options,
    )


def _needed_columns(options: Mapping[str, Any]) -> list[str]:
    extra = [options[k] for k in ("time_column", "experiment_column") if options[k] is not None]
    return list(options["inputs"]) + list(options["outputs"]) + extra


def _check_columns(available: Sequence[str], needed: Sequence[str], where: _Where) -> None:
    """Raise for the first needed column that is missing, with suggestions."""
    # Blank header cells (e.g. from trailing delimiters) only clutter the list.
    shown = [a for a in available if not re.fullmatch(r"Unnamed: \d+", a)]
    for wanted in needed:
        if wanted not in available:
            message = _unknown_name_message(where.prefix, where.label, wanted, shown)
            if available and all(_looks_numeric(a) for a in available):
                message += " (the first line is read as the header; add a line of column names)"
            raise DataError(message)


def _looks_numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


# .csv / .tsv / .txt ----------------------------------------------------------------
def _sniff_delimiter(sample: str, suffix: str, truncated: bool) -> str:
    """The delimiter present on each of the first lines (same count first), else a default."""
    lines = [line for line in sample.splitlines() if line.strip()]
    if truncated and len(lines) > 1:
        lines = lines[:-1]  # the last line may be cut short
    lines = lines[:50]
    counts = {d: [line.count(d) for line in lines] for d in _DELIMITERS[suffix]}
    for delimiter, found in counts.items():
        if found and found[0] > 0 and all(c == found[0] for c in found):
            return delimiter
    for delimiter, found in counts.items():  # quoted fields may hide extra delimiters
        if found and all(c > 0 for c in found):
            return delimiter
    return "," if suffix == ".csv" else _WHITESPACE


def _encoding(head: bytes) -> str:
    """UTF-8 (with or without a byte-order mark) when the file's first bytes decode as
    it, else Windows-1252 (a superset of Latin-1 for text: ``courant_é`` written by a
    spreadsheet on Windows), so that column names read as the user typed them."""
    try:
        head.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 4:  # not a character cut at the end of the sample
            return "cp1252"
    return "utf-8-sig"


def _csv_options(delimiter: str, encoding: str = "utf-8-sig") -> dict[str, Any]:
    options: dict[str, Any] = {
        "sep": delimiter,
        "encoding": encoding,
        "encoding_errors": "replace",
        "engine": "c",
    }
    if delimiter != _WHITESPACE:
        options["skipinitialspace"] = True
    return options


def _records(lines: Iterable[str], delimiter: str) -> Iterator[tuple[int, list[str]]]:
    """``(line number, fields)`` of the non-blank records, counted the way pandas does."""
    if delimiter == _WHITESPACE:
        records = ((n, line.split()) for n, line in enumerate(lines, start=1))
    else:
        reader = csv.reader(lines, delimiter=delimiter, skipinitialspace=True)
        records = ((reader.line_num, fields) for fields in reader)
    for line, fields in records:
        if fields and not (len(fields) == 1 and not fields[0].strip()):
            yield line, fields


def _text_locator(path: Path, delimiter: str, encoding: str = "utf-8-sig") -> Locator:
    """Map 0-based data rows to ``(line number, {column: raw text})`` by re-reading the file.

    The first non-blank record is the header, as for pandas. Used only to word an error
    message, so the file is read again only when something is wrong.
    """

    def locate(rows: Sequence[int]) -> dict[int, tuple[int, dict[str, str]]]:
        wanted, last = set(rows), max(rows)
        found: dict[int, tuple[int, dict[str, str]]] = {}
        with open(path, encoding=encoding, errors="replace", newline="") as handle:
            records = _records(handle, delimiter)
            header = [name.strip() for name in next(records, (0, []))[1]]
            for row, (line, fields) in enumerate(records):
                if row in wanted:
                    found[row] = (line, dict(zip(header, fields, strict=False)))
                if row >= last:
                    break
        return found

    return locate


def _check_extra_fields(sample: str, delimiter: str, shown: str) -> None:
    """Raise if the first rows carry values beyond the header's last column.

    pandas drops such fields (with a warning); empty ones come from trailing delimiters
    and are harmless, but values there mean the header lacks names.
    """
    records = _records(sample.splitlines()[:1000], delimiter)
    header = next(records, (0, []))[1]
    for line, fields in records:
        extra = [f for f in fields[len(header) :] if f.strip()]
        if extra:
            raise DataError(
                f"{shown}: line {line} has {len(fields)} fields but the header names only "
                f"{len(header)} columns; add names for the extra columns or remove them"
            )


def _read_text(
    path: Path, shown: str, suffix: str, options: Mapping[str, Any]
) -> tuple[pd.DataFrame, _Where, str]:
    with open(path, "rb") as handle:
        head = handle.read(_SNIFF_BYTES)
    if b"\x00" in head:  # text in UTF-8 or a Windows code page never holds a NUL byte
        raise DataError(
            f"{shown} is not a text file: it holds NUL bytes (binary or compressed data, or "
            "UTF-16 text); save the data as delimited text in UTF-8, or as .parquet or .mat"
        )
    encoding = _encoding(head)
    sample = head.decode(encoding, errors="replace")
    if not sample.strip():
        raise DataError(f"{shown} is empty (only blank lines)")
    delimiter = _sniff_delimiter(sample, suffix, truncated=len(head) == _SNIFF_BYTES)
    where = _Where(shown, locate=_text_locator(path, delimiter, encoding))
    try:
        # All columns are parsed (no usecols), so that pandas reports rows with more
        # fields than the header; index_col=False stops it from silently turning the
        # first column into the index when every row has one field too many.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", pd.errors.ParserWarning)
            frame = pd.read_csv(path, index_col=False, **_csv_options(delimiter, encoding))
    except pd.errors.EmptyDataError:
        raise DataError(f"{shown} is empty (no header line)") from None
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError) as exc:
        reason = str(exc).replace("Error tokenizing data. C error: ", "").strip()
        raise DataError(
            f"{shown} could not be parsed as delimited text: {reason}; every row needs one "
            "field per header column"
        ) from None
    if any(issubclass(w.category, pd.errors.ParserWarning) for w in caught):
        _check_extra_fields(sample, delimiter, shown)
    frame.columns = [str(c).strip() for c in frame.columns]
    header = [name.strip() for name in next(_records(sample.splitlines(), delimiter), (0, []))[1]]
    needed = _needed_columns(options)
    if len(header) == frame.shape[1]:
        _check_duplicates(header, needed, where)
        _check_grouped_header(header, frame, needed, shown)
    _check_columns(list(frame.columns), needed, where)
    return frame, where, f"{shown} has a header but no data rows"


def _check_duplicates(header: Sequence[str], needed: Sequence[str], where: _Where) -> None:
    """Raise if a needed column name appears more than once in the header.

    pandas renames the second ``u`` to ``u.1`` and the first would be used without a
    word; which one the user meant cannot be guessed.
    """
    for wanted in needed:
        positions = [k + 1 for k, name in enumerate(header) if name == wanted]
        if len(positions) > 1:
            raise DataError(
                f"{where.prefix}{where.label} '{wanted}' appears {len(positions)} times in the "
                f"header ({where.label}s {_and(positions)}); give every {where.label} a "
                "unique name"
            )


def _check_grouped_header(
    header: Sequence[str], frame: pd.DataFrame, needed: Sequence[str], shown: str
) -> None:
    """Raise if a needed column heads a group of unnamed columns that hold data.

    Some files name groups of columns (``"r",,,,"u",,,,"y",,,`` : one name over the
    columns of several periods or experiments); read column by column, only the first
    of each group would be used and the others dropped without a word.
    """
    groups = []
    for wanted in needed:
        if wanted not in header:
            continue
        first = header.index(wanted)
        last = first
        while (
            last + 1 < len(header)
            and not header[last + 1]
            and frame.iloc[:, last + 1].notna().any()
        ):
            last += 1
        if last > first:
            groups.append((wanted, first + 1, last + 1))
    if not groups:
        return
    unnamed = sum(last - first for _, first, last in groups)
    where = "; ".join(
        f"'{name}' (column {first}) is followed by {last - first} columns without a name "
        f"({_span(first + 1, last)})"
        for name, first, last in groups
    )
    raise DataError(
        f"{shown} has a grouped header: {where}. Each name seems to stand over a group of "
        f"columns (e.g. one per period or experiment), and only the first column of each "
        f"group would be read, dropping {unnamed} unnamed columns that hold data. Give every "
        "column its own name in the header line (e.g. u1,u2,...), or read the file yourself "
        "and build the data with Dataset.from_frame (one experiment per column group)"
    )


def _and(numbers: Sequence[int]) -> str:
    return ", ".join(map(str, numbers[:-1])) + f" and {numbers[-1]}"


def _span(first: int, last: int) -> str:
    return f"column {first}" if first == last else f"columns {first} to {last}"


# .parquet ----------------------------------------------------------------------------
def _read_parquet(
    path: Path, shown: str, options: Mapping[str, Any]
) -> tuple[pd.DataFrame, _Where, str]:
    import pyarrow as pa
    import pyarrow.parquet as pq

    where = _Where(shown)
    try:
        schema = pq.read_schema(path)
    except (pa.ArrowException, OSError) as exc:
        raise DataError(f"{shown} is not a readable Parquet file ({exc})") from None
    available = [n for n in schema.names if not n.startswith("__index_level_")]
    needed = _needed_columns(options)
    _check_duplicates(available, needed, where)
    _check_columns(available, needed, where)
    if options["sampling_time"] is not None and options["time_column"] is None:
        # read a time-like column too, so that a contradicting sampling time is caught
        needed += [n for n in _time_like(available) if n not in needed and available.count(n) == 1]
    try:
        frame = pq.read_table(path, columns=needed).to_pandas()
    except (pa.ArrowException, OSError) as exc:
        raise DataError(f"{shown} could not be read as Parquet ({exc})") from None
    return frame, where, f"{shown} has columns but no data rows"


# .mat ---------------------------------------------------------------------------------
def _read_mat(path: Path, shown: str, name: str, several: bool, **options: Any) -> Dataset:
    from scipy.io import loadmat, whosmat
    from scipy.io.matlab import MatReadError, matfile_version

    try:
        major, _ = matfile_version(str(path))
    except (MatReadError, ValueError, OSError) as exc:
        raise DataError(f"{shown} is not a MATLAB .mat file ({exc})") from None
    if major == 2:
        raise DataError(
            f"{shown} is a MATLAB v7.3 (HDF5) file, which blockid cannot read; re-save it "
            "in MATLAB with save(filename, ..., '-v7') or export the signals to CSV"
        )
    where = _Where(shown, label="variable", row_label="sample")
    try:
        listing = {entry[0]: entry for entry in whosmat(str(path))}
        needed = _needed_columns(options)
        _check_columns(list(listing), needed, where)
        contents = loadmat(str(path), variable_names=needed)
    except (MatReadError, ValueError, TypeError, OSError) as exc:
        if isinstance(exc, DataError):
            raise
        raise DataError(f"{shown} could not be read as a MATLAB file ({exc})") from None

    arrays = {v: _mat_matrix(contents[v], v, listing[v][2], shown) for v in needed}
    n_rows, n_cols = max((a.shape for a in arrays.values()), key=lambda s: s[1])
    for variable, array in arrays.items():
        broadcast = variable == options["time_column"] and array.shape == (n_rows, 1)
        if array.shape != (n_rows, n_cols) and not broadcast:
            shapes = ", ".join(
                f"'{v}' is {' x '.join(map(str, contents[v].shape))}" for v in needed
            )
            raise DataError(
                f"{shown}: variables have different shapes ({shapes}); every signal needs "
                "one value per sample: a vector for one experiment, or an N x E matrix "
                "with one experiment per column"
            )
    datasets = []
    for j in range(n_cols):
        label = name if n_cols == 1 else f"{name} column {j + 1}"
        frame = pd.DataFrame({v: a[:, min(j, a.shape[1] - 1)] for v, a in arrays.items()})
        column_source = shown if n_cols == 1 else f"{shown} (column {j + 1})"
        column_where = _Where(column_source, label="variable", row_label="sample")
        datasets.append(
            _frame_to_dataset(
                frame,
                source=column_source,
                name=label,
                split_prefix=label if several or n_cols > 1 else None,
                where=column_where,
                **options,
            )
        )
    return datasets[0] if n_cols == 1 else _concat(datasets, source=shown)


def _mat_matrix(value: Any, variable: str, matlab_class: str, shown: str) -> np.ndarray:
    """A .mat variable as a float (N, E) array; vectors of either orientation give E = 1."""
    if not isinstance(value, np.ndarray) or value.dtype.kind not in "biuf":
        kind = (
            "complex"
            if getattr(value, "dtype", None) is not None and value.dtype.kind == "c"
            else matlab_class
        )
        raise DataError(
            f"{shown}: variable '{variable}' is a {kind} array, not a real numeric vector or matrix"
        )
    if value.ndim > 2:
        raise DataError(
            f"{shown}: variable '{variable}' has {value.ndim} dimensions; use a vector "
            "(one experiment) or an N x E matrix (one experiment per column)"
        )
    if value.size == 0:
        raise DataError(f"{shown}: variable '{variable}' is empty")
    if value.ndim == 1 or 1 in value.shape:
        return value.reshape(-1, 1).astype(np.float64)
    return value.astype(np.float64)


# ---------------------------------------------------------------------- writing
def write_table(frame: pd.DataFrame, path: PathLike, overwrite: bool = False) -> Path:
    """Write a DataFrame to ``.csv``, ``.tsv`` or ``.parquet`` atomically.

    The table is written to a temporary file in the same folder, flushed to disk and
    then renamed over ``path``, so ``path`` holds either the old or the complete new
    content, never a partial file. The index is not written.

    Parameters
    ----------
    frame : DataFrame
        The table.
    path : path
        Target file; the suffix picks the format.
    overwrite : bool
        Replace an existing file (the CLI's ``--force``).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    DataError
        If the suffix is unknown, the file exists and ``overwrite`` is false, the folder
        does not exist or the file cannot be written.
    """
    target = Path(path)
    suffix = check_table_target(target)

    def write(handle: IO[bytes]) -> None:
        if suffix == ".parquet":
            frame.to_parquet(handle, index=False)
        else:
            frame.to_csv(handle, index=False, sep="\t" if suffix == ".tsv" else ",")

    return _atomic_write(target, overwrite, write)


def write_text_atomic(text: str, path: PathLike, overwrite: bool = False) -> Path:
    """Write UTF-8 text (e.g. a JSON model file) atomically; see :func:`write_table`.

    Raises
    ------
    DataError
        If the file exists and ``overwrite`` is false, or it cannot be written.
    """
    data = text.encode("utf-8")
    return _atomic_write(Path(path), overwrite, lambda handle: handle.write(data))


def _atomic_write(target: Path, overwrite: bool, write: Callable[[IO[bytes]], Any]) -> Path:
    """Write through a temporary sibling file, fsync it, then ``os.replace`` it over the
    target. A symbolic link is kept and its target written (atomically); a device or a
    pipe (:func:`is_stream`) is written directly, as a stream."""
    if is_stream(target):
        try:
            with open(target, "wb") as handle:
                write(handle)
                handle.flush()
        except OSError as exc:
            raise DataError(f"could not write {target}: {exc.strerror or exc}") from exc
        return target
    if target.is_symlink():
        target = Path(os.path.realpath(target))
    if target.is_dir():
        raise DataError(f"cannot write {target}: it is a folder")
    if target.exists() and not overwrite:
        raise DataError(
            f"{target} already exists; pass overwrite=True to replace it", parameter="overwrite"
        )
    folder = target.parent
    if not folder.is_dir():
        raise DataError(f"cannot write {target}: folder {folder} does not exist")
    temporary = folder / f".{target.name}.{secrets.token_hex(6)}.tmp"
    try:
        with open(temporary, "xb") as handle:
            write(handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, target)
    except OSError as exc:
        raise DataError(f"could not write {target}: {exc.strerror or exc}") from exc
    finally:
        try:
            temporary.unlink(missing_ok=True)
        except OSError:
            pass
    return target


def json_safe(value: Any) -> Any:
    """A copy of a JSON-ready document with every NaN or infinite float as ``None``.

    JSON has no NaN or infinity (``json.dumps(..., allow_nan=False)`` refuses them);
    an undefined number (the fit percent of a constant output) is written as
    ``null`` instead. Dictionaries, lists and tuples
    are copied; NumPy scalars become Python numbers.

    >>> json_safe({"fit_percent": {"y": float("nan")}, "mse": [1.0, float("inf")]})
    {'fit_percent': {'y': None}, 'mse': [1.0, None]}
    """
    if isinstance(value, Mapping):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_text(doc: Any) -> str:
    """``doc`` as the JSON text the commands print and write: :func:`json_safe` (an
    undefined number is ``null``), indented by two spaces, ending in a newline.

    >>> print(json_text({"fit_percent": float("nan")}), end="")
    {
      "fit_percent": null
    }
    """
    return json.dumps(json_safe(doc), indent=2, allow_nan=False) + "\n"
