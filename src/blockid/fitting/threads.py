"""How many threads one fit may use, and the normal equations summed on them.

A fit on free-run simulation error spends its time in two places per iteration
(``docs/performance.md``): the walk of the output sensitivities (a compiled kernel
whose column blocks run on numba's threads) and ``J^T J`` (BLAS). Both are split by a
**fixed partition** — the kernel's column blocks, and here column tiles of ``J^T J``
that depend on the number of parameters only — and every tile is summed piece after
piece in the record's order by single-threaded BLAS, so the result is the same, bit for
bit, whatever the number of threads or the machine.

By default a fit takes every core this process may use; :func:`fit_threads` limits
it (``identify``'s worker processes, which share the cores already, use one each).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from blockid.config import get_config

__all__ = [
    "MIN_TILE",
    "NormalSums",
    "fit_threads",
    "kernel_threads",
    "set_fit_threads",
    "share_threads",
    "threads_for_fit",
]

#: The narrowest column block that is still worth a tile of its own.
MIN_TILE = 64

_limit: int | None = None  # None: every core the process may use
#: A one-element array a worker process's fits read their thread allowance from
#: (:func:`share_threads`); None: no allowance beyond the limit.
_shared: np.ndarray | None = None


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def threads_for_fit() -> int:
    """The threads a fit may use now (:func:`fit_threads`, else every core; raised to
    the allowance of :func:`share_threads` when one is shared); a fit asks at each
    iteration, so an allowance raised while it runs is taken from its next one."""
    n = _cores() if _limit is None else _limit
    if _shared is not None:
        n = max(n, int(_shared[0]))
    return max(1, min(n, _cores()))


def share_threads(allowance: np.ndarray | None) -> None:
    """Every later fit of this process may take ``int(allowance[0])`` threads, read at
    each of its iterations (a worker of :class:`~blockid.workflows.parallel.TaskRunner`,
    whose runner raises it while cores are idle); None: no shared allowance."""
    global _shared
    _shared = allowance


def set_fit_threads(n: int | None) -> None:
    """Every later fit of this process uses at most ``n`` threads (None: every core);
    a worker process that shares the cores with others says 1."""
    global _limit
    _limit = None if n is None else max(1, int(n))


@contextmanager
def fit_threads(n: int | None) -> Iterator[None]:
    """Fits inside the block use at most ``n`` threads (None: every core). The
    result does not depend on it (module docstring), only the time."""
    global _limit
    before, _limit = _limit, (None if n is None else max(1, int(n)))
    try:
        yield
    finally:
        _limit = before


@contextmanager
def kernel_threads(n: int) -> Iterator[None]:
    """numba's parallel kernels launched from this thread use ``n`` threads (at most
    the ``NUMBA_NUM_THREADS`` the process started with) inside the block."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(max(1, min(n, numba.config.NUMBA_NUM_THREADS)))
    try:
        yield
    finally:
        numba.set_num_threads(before)


def _tiles(n: int) -> tuple[tuple[slice, slice], ...]:
    """The upper triangle of an ``n x n`` matrix in fixed tiles (about ``tile_columns``
    columns, :mod:`blockid.config`: fixed by the number of parameters, never by the
    number of threads; at least two column blocks from ``2 * MIN_TILE`` columns on, so
    that a mid-sized problem's three products share two threads)."""
    return _tile_cut(n, get_config()["tile_columns"], MIN_TILE)


@functools.lru_cache(maxsize=64)
def _tile_cut(n: int, tile: int, least: int) -> tuple[tuple[slice, slice], ...]:
    count = max(round(n / tile), 2 if n >= 2 * least else 1)
    edges = np.linspace(0, n, count + 1).astype(int)
    cuts = [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]
    return tuple((cuts[i], cuts[j]) for i in range(count) for j in range(i, count))


class NormalSums:
    """``J^T J``, ``-J^T r`` and ``r^T r`` of a Jacobian given piece by piece, the
    tiles of ``J^T J`` on ``threads`` threads (module docstring); use as a context
    manager (the threads live inside it).

    Each piece is ``J`` (rows, p) and ``r`` over the columns ``cols`` (p indices into
    the ``n`` unknowns: an experiment's pieces fill its own initial state's columns).
    """

    def __init__(self, n: int, threads: int = 1) -> None:
        self.n = n
        self.H = np.zeros((n, n))
        self.g = np.zeros(n)
        self.cost = 0.0
        # one tile (a small problem): summed by the caller, no pool to hand it to
        self.threads = max(1, int(threads)) if len(_tiles(n)) > 1 else 1
        self.pool: Any = None
        self.blas: Any = None
        self.pending: list[Any] = []

    def __enter__(self) -> NormalSums:
        from threadpoolctl import threadpool_limits

        self.blas = threadpool_limits(limits=1)  # each tile on one BLAS thread
        if self.threads > 1:
            from concurrent.futures import ThreadPoolExecutor

            self.pool = ThreadPoolExecutor(self.threads, thread_name_prefix="blockid-tiles")
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=exc[0] is not None)
        self.blas.restore_original_limits()

    def add(self, J: np.ndarray, r: np.ndarray, cols: np.ndarray) -> None:
        """Add one piece. With threads, its tiles are summed while the caller walks the
        next piece; the next :meth:`add` (or :meth:`result`) waits for them first, so
        every tile's sum still runs in the record's order. ``J`` must not be changed
        until then."""
        self.wait()
        r = r.reshape(-1)
        self.cost += float(r @ r)
        self.g[cols] -= J.T @ r
        whole = cols.size == self.n and bool(np.all(cols == np.arange(self.n)))

        def tile(pair: tuple[slice, slice]) -> None:
            a, b = pair
            block = J[:, a].T @ J[:, b]
            if whole:
                self.H[a, b] += block
            else:
                self.H[np.ix_(cols[a], cols[b])] += block

        pairs = _tiles(cols.size)
        if self.pool is None:
            for pair in pairs:
                tile(pair)
        else:
            self.pending = [self.pool.submit(tile, pair) for pair in pairs]

    def wait(self) -> None:
        """Until the last piece's tiles are summed (its ``J`` free to be reused)."""
        pending, self.pending = self.pending, []
        for future in pending:
            future.result()

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """``J^T J`` (its upper tiles mirrored) and ``-J^T r``."""
        self.wait()
        upper = np.triu(self.H)
        return upper + np.triu(upper, 1).T, self.g
