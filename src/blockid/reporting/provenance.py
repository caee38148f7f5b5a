"""What produced a report: the command, the data files' SHA-256 and the versions.

Versions are read from the installed distributions' metadata, so recording them does
not import NumPy, SciPy, numba or pandas.
"""

from __future__ import annotations

import datetime
import hashlib
import platform
import shlex
import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

__all__ = ["DataFile", "Provenance", "collect_provenance", "file_sha256", "versions"]

#: Distributions whose versions a report records, in this order.
PACKAGES = ("blockid", "numpy", "scipy", "numba", "pandas", "matplotlib")


@dataclass(frozen=True)
class DataFile:
    """One data file: its path as given, its size in bytes and its SHA-256 (hex)."""

    path: str
    size: int
    sha256: str


@dataclass(frozen=True)
class Provenance:
    """The exact command, data files, versions and date (UTC, ISO 8601) of a report."""

    command: str
    files: tuple[DataFile, ...] = ()
    versions: dict[str, str] = field(default_factory=dict)
    date: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {
            "command": self.command,
            "files": [vars(f) for f in self.files],
            "versions": dict(self.versions),
            "date": self.date,
        }


def file_sha256(path: str | Path, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes, as 64 hexadecimal digits (read in 1 MiB chunks).

    >>> import tempfile, os
    >>> with tempfile.NamedTemporaryFile(delete=False) as f:
    ...     _ = f.write(b"abc")
    >>> file_sha256(f.name)[:16]
    'ba7816bf8f01cfea'
    >>> os.remove(f.name)
    """
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        while block := handle.read(chunk):
            digest.update(block)
    return digest.hexdigest()


def versions() -> dict[str, str]:
    """Versions of blockid, its numerical dependencies, Python and the platform."""
    out: dict[str, str] = {}
    for name in PACKAGES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    if out["blockid"] == "not installed":  # running from a source tree
        from blockid import __version__

        out["blockid"] = __version__
    out["python"] = platform.python_version()
    out["platform"] = platform.platform()
    return out


def collect_provenance(
    paths: Iterable[str | Path] = (),
    argv: Sequence[str] | None = None,
    now: datetime.datetime | None = None,
) -> Provenance:
    """The provenance of a report made now from the data files ``paths``.

    ``argv`` is the command line (default ``sys.argv``); its first word is shown by
    its file name (``blockid``, not the full path of the script).
    """
    words = list(sys.argv if argv is None else argv)
    if words:
        words[0] = Path(words[0]).name
    files = tuple(
        DataFile(str(p), Path(p).stat().st_size, file_sha256(p)) for p in dict.fromkeys(paths)
    )
    when = (now or datetime.datetime.now(datetime.UTC)).replace(microsecond=0)
    return Provenance(shlex.join(words), files, versions(), when.isoformat())
