"""Memory and work-partition sizes of the fits: one place to read and set them.

A long record is never held whole: regressors, Jacobians and their normal equations are
built piece by piece. How big a piece is trades memory against speed (fewer, larger
pieces: less overhead per piece, more memory), and the pieces also fix the order in which
floating-point sums are added. So a fit is reproducible bit for bit for a given setting,
on any machine and with any number of threads or workers, and changing a setting may
change the last bits of its result (``jacobian_bytes`` may change more: it picks the
solver). The defaults suit records of millions of samples on a machine with a few GB.

The fits read the settings when they run (never at import), so a setting applies to
every fit started after it, here and in ``identify``'s worker processes or dask workers
(:class:`~blockid.workflows.parallel.TaskRunner` sends them with each task; ``fleet``'s
dask workers fit with their own process's settings, the defaults unless set there).
The settings are the process's, not a thread's: fits running in two threads at once
see the same ones.

>>> from blockid.config import config_context, get_config
>>> get_config()["regressor_rows"]
65536
>>> with config_context(regressor_rows=2048):
...     get_config()["regressor_rows"]
2048
>>> get_config()["regressor_rows"]
65536

``docs/performance.md`` (section "Memory and work-partition sizes") has the table and
the measurements behind the defaults. Plain Python, no imports of NumPy: the command line
may read it before it imports anything numerical.
"""

from __future__ import annotations

import operator
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

__all__ = ["SETTINGS", "Setting", "config_context", "get_config", "set_config"]


@dataclass(frozen=True)
class Setting:
    """One size: its default, the least value allowed, its unit and what it trades."""

    default: int
    low: int
    unit: str
    help: str


#: Every size, by name: its default, least value, unit and what it trades.
SETTINGS: dict[str, Setting] = {
    "regressor_rows": Setting(
        1 << 16, 1, "rows",
        "ARX regressors (and the initial estimates' regressions) built this many rows at "
        "a time: memory about rows x regressors x 8 bytes; batch least squares folds "
        "them into its factor piece after piece, so the pieces fix its sums",
    ),
    "jacobian_bytes": Setting(
        64 * 2**20, 0, "bytes",
        "largest Jacobian (fitted samples x free parameters x 8 bytes) a chain's "
        "simulation-error refinement forms whole (scipy's least_squares); above it the "
        "normal equations are summed piece by piece and Levenberg-Marquardt solves them "
        "(a different solver: the result may differ beyond the last bits); 0: always "
        "in pieces",
    ),
    "sensitivity_rows": Setting(
        1 << 16, 1, "samples",
        "samples per piece of a chain's sensitivity walk above jacobian_bytes: memory "
        "about samples x parameters x 8 bytes; the pieces fix the sums of J^T J",
    ),
    "state_space_rows": Setting(
        4096, 1, "samples",
        "samples per piece of a state-space model's Jacobian walk (the refinement, the "
        "initial state, the standard errors) and columns per step of the subspace "
        "method's LQ factorisation: memory about two pieces of samples x outputs x "
        "parameters x 8 bytes; the pieces fix the sums",
    ),
    "tile_columns": Setting(
        448, 1, "columns",
        "columns of J^T J per tile (about; fixed by the number of parameters, never by "
        "the number of threads): the tiles are summed side by side on a fit's threads, "
        "each in the record's order, so the tiles fix the sums",
    ),
    "history_rows": Setting(
        20_000, 1, "rows",
        "most parameter vectors a recursive fit's recorded history keeps (every "
        "stride-th update beyond): memory about rows x parameters x 8 bytes; the "
        "estimates do not depend on it",
    ),
}  # fmt: skip

_config: dict[str, int] = {name: s.default for name, s in SETTINGS.items()}


def get_config() -> dict[str, int]:
    """The sizes now in force, by name (a copy: change them with :func:`set_config` or
    :func:`config_context`)."""
    return dict(_config)


def _checked(values: dict[str, Any]) -> dict[str, int]:
    """``values`` as whole numbers, or a ValueError naming the size and its range."""
    out = {}
    for name, value in values.items():
        if name not in SETTINGS:
            raise ValueError(
                f"{name!r} is not a blockid setting; choose one of {', '.join(SETTINGS)}"
            )
        low = SETTINGS[name].low
        try:
            number = operator.index(value) if not isinstance(value, bool) else None
        except TypeError:
            number = None
        if number is None or number < low:
            raise ValueError(
                f"{name}={value!r} must be a whole number >= {low} ({SETTINGS[name].unit})"
            )
        out[name] = int(number)
    return out


def set_config(**values: int) -> None:
    """Set sizes for every later fit of this process (names and ranges: :data:`SETTINGS`;
    a bad name or value changes nothing and raises ValueError)."""
    _config.update(_checked(values))


@contextmanager
def config_context(**values: int) -> Iterator[None]:
    """Sizes set inside the block, and every size as it was after it (even on an error)."""
    changed = _checked(values)
    before = dict(_config)
    _config.update(changed)
    try:
        yield
    finally:
        _config.clear()
        _config.update(before)
