"""Checks on file paths that need no numerical library: data files to read, targets to
write.

The command line runs them before it imports NumPy, pandas or numba, so that a missing
file, a folder given as data or an unknown suffix is answered at once
(:func:`check_data_paths`); :func:`blockid.data.read_data` runs the same checks.
"""

from __future__ import annotations

import difflib
import json
import os
import stat
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from blockid.errors import DataError, ModelFileError

__all__ = [
    "READ_SUFFIXES",
    "WRITE_SUFFIXES",
    "check_data_paths",
    "check_file",
    "check_suffix",
    "check_table_target",
    "is_stream",
    "read_model_document",
]

#: File suffixes :func:`blockid.data.read_data` can read.
READ_SUFFIXES = (".csv", ".tsv", ".txt", ".parquet", ".mat")
#: File suffixes :func:`blockid.data.write_table` can write.
WRITE_SUFFIXES = (".csv", ".tsv", ".parquet")

PathLike = str | os.PathLike


def check_suffix(path: Path) -> str:
    """The lower-case suffix of ``path``, one of :data:`READ_SUFFIXES`."""
    return _suffix(path, READ_SUFFIXES, f"{path}: unknown data file type", "supported:")


def check_file(path: Path, shown: str) -> None:
    """Existence, type and size checks that every reader starts with (``shown``: the
    path as the user wrote it)."""
    if not path.exists():
        folder = path.parent
        if not folder.is_dir():
            raise DataError(f"{shown} does not exist (no folder {folder})")
        siblings = sorted(p.name for p in folder.iterdir() if p.is_file())
        near = difflib.get_close_matches(path.name, siblings, n=3, cutoff=0.6)
        hint = f" (did you mean {' or '.join(repr(n) for n in near)}?)" if near else ""
        raise DataError(f"{shown} does not exist{hint}")
    if path.is_dir():
        raise DataError(f"{shown} is a folder, not a data file")
    if path.stat().st_size == 0:
        raise DataError(f"{shown} is empty")


def check_data_paths(paths: PathLike | Sequence[PathLike]) -> list[str]:
    """Check data file paths before reading any: at least one, no folder, a known
    suffix, existing and not empty, none listed twice. Returns them as given (text)."""
    path_list = [paths] if isinstance(paths, str | os.PathLike) else list(paths)
    if not path_list:
        raise DataError("no data file given; name at least one .csv, .parquet or .mat file")
    shown = [str(p) for p in path_list]
    for text in shown:
        if Path(text).is_dir():
            raise DataError(
                f"{text} is a folder, not a data file; name the files in it (e.g. {text}/*.csv)"
            )
        check_suffix(Path(text))
        check_file(Path(text), text)
    resolved = [os.path.realpath(p) for p in shown]
    for i, real in enumerate(resolved):
        if real in resolved[:i]:
            raise DataError(f"{shown[i]} is listed twice; give each data file once")
    return shown


def check_table_target(path: PathLike) -> str:
    """The lower-case suffix of a table to write, one of :data:`WRITE_SUFFIXES`."""
    target = Path(path)
    problem = f"cannot write {target}: unknown table type"
    return _suffix(target, WRITE_SUFFIXES, problem, "use one of")


def _suffix(path: Path, allowed: tuple[str, ...], problem: str, fix: str) -> str:
    suffix = path.suffix.lower()
    if suffix not in allowed:
        raise DataError(f"{problem} {suffix or '(no suffix)'!r}; {fix} {', '.join(allowed)}")
    return suffix


def is_stream(path: PathLike) -> bool:
    """True for an existing path (or a link to one) that is not a regular file or a
    folder: a device (``/dev/full``), a named pipe, ``/dev/stdout``. Such a target is
    written through, never replaced by a file."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def read_model_document(path: PathLike) -> Any:
    """The JSON document of a model file, or a :class:`~blockid.errors.ModelFileError`
    that says what is wrong with the file (missing, a folder, empty, not text, not JSON)."""
    path = Path(path)
    if path.is_dir():
        raise ModelFileError(f"{path} is a folder, not a model file; name the .json file in it")
    if not path.is_file():
        raise ModelFileError(f"model file {path} does not exist")
    try:
        text = path.read_text(encoding="utf-8")
        if not text.strip():
            raise ModelFileError(f"model file {path} is empty; refit the model or restore the file")
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(
            f"{path} is not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg}); "
            "the file is damaged: refit or restore it"
        ) from None
    except UnicodeDecodeError:
        raise ModelFileError(f"{path} is not a text file; is it really a model file?") from None
