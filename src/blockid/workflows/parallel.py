"""Run many fits on one data set in worker processes, with results in a fixed order.

:class:`TaskRunner` runs a top-level function ``fn(data, item)`` over a list of items,
either here (``jobs = 1``) or in ``jobs`` worker processes of the standard library's
:class:`concurrent.futures.ProcessPoolExecutor`. Either way the results come back as a
list in the order of the items, whatever order the workers finish in, so a search that
merges them gives the same answer with one worker or two.

* **The data are shared, not copied.** The record is written once into one block of
  shared memory (:mod:`multiprocessing.shared_memory`); every worker maps it and builds
  the same :class:`~blockid.data.dataset.Dataset` of read-only views on it, so two
  workers on a long record cost one copy of it, not three.
* **Fresh worker processes** (:mod:`loky`: fork then exec on POSIX, functions sent
  with cloudpickle, so a plain script needs no ``if __name__ == "__main__"`` guard).
  Workers forked from a process whose OpenBLAS had started its threads kept a thread
  spinning beside each fit even with the pool limited to one thread: on a 20 000-sample
  Hammerstein-Wiener fit each task took 12-18 s in two forked workers against 4.5 s
  in one process, and two workers were slower than one. A fresh worker starts with
  ``OPENBLAS_NUM_THREADS=1`` (and the OpenMP, MKL and numba counterparts) in its
  environment, so those threads never exist.
* **Same arithmetic everywhere.** Every fit, here or in a worker, runs with the BLAS and
  OpenMP thread pools limited to one thread (the environment above in a worker,
  :mod:`threadpoolctl` here): the results do not depend on how the work is spread, and
  ``jobs`` workers use ``jobs`` cores.
* **Or on a cluster.** Given a ``scheduler`` (a ``dask.distributed`` address, cluster or
  client), the items go to the cluster's workers as tasks instead: the record is sent
  to every worker once (``Client.scatter(..., broadcast=True)``), not with each task;
  each task runs with one thread in every pool, like a local worker, so the results are
  those of ``jobs = 1`` bit for bit. The workers must be able to import blockid (the
  same version: the arithmetic is the same only with the same code).
* **The last fits take the idle cores.** While fewer items are unfinished than there
  are workers (the last wave of a stage: three folds on two workers leave one core
  idle while the third fit runs), each running fit may take ``jobs // unfinished``
  threads: the runner writes that allowance into the shared memory after every
  result, and a worker's fit reads it at each of its iterations
  (:func:`blockid.fitting.threads.share_threads`; the workers' numba pools are sized
  to ``jobs`` for it, BLAS stays at one thread). A fit's result does not depend on its
  threads (:mod:`blockid.fitting.threads`), so neither does the search's.
* **The same sizes everywhere.** Each task carries the memory and work-partition sizes
  in force where it was submitted (:func:`blockid.config.get_config`), and runs under
  them in its worker: the pieces fix the order of the sums, so a setting gives the
  model of ``jobs = 1`` with any number of workers.
* **A cap, not a budget.** :meth:`TaskRunner.map` takes a ``deadline`` (a
  :func:`time.monotonic` value): items not started by then are cancelled and their
  results are None. The caller says so; nothing else depends on the clock.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from blockid.config import config_context, get_config
from blockid.data.dataset import Dataset, Experiment
from blockid.workflows.effort import MAX_JOBS

__all__ = ["MISSING_DASK", "TaskRunner", "available_cores"]

#: Seconds to wait for a dask scheduler to answer before saying it cannot be reached
#: (:class:`TaskRunner`'s ``connect_timeout``).
CONNECT_TIMEOUT = 10.0
#: What to do when a scheduler is given and dask.distributed is not installed.
MISSING_DASK = "a dask scheduler needs dask.distributed: pip install 'blockid[fleet]'"

#: Set in each worker process by :func:`_start_worker`.
_WORKER_DATA: Dataset | None = None
_WORKER_MEMORY: Any = None


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


#: The environment of a worker process: one thread in every numerical thread pool.
WORKER_ENV = {
    name: "1"
    for name in (
        "OMP_NUM_THREADS",
        "OPENBLAS_NUM_THREADS",
        "MKL_NUM_THREADS",
        "BLIS_NUM_THREADS",
        "VECLIB_MAXIMUM_THREADS",
        "NUMBA_NUM_THREADS",
    )
}


def _single_threaded() -> Any:
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1)


def _layout(data: Dataset) -> tuple[list[tuple[str, int]], int]:
    """``(name, samples)`` per experiment and the floats they need (u then y, row major)."""
    shapes = [(e.name, e.n_samples) for e in data.experiments]
    width = data.n_inputs + data.n_outputs
    return shapes, sum(n for _, n in shapes) * width


def _views(buffer: Any, data_meta: tuple[Any, ...]) -> Dataset:
    inputs, outputs, ts, source, shapes = data_meta
    nu, ny = len(inputs), len(outputs)
    flat = np.ndarray((sum(n for _, n in shapes) * (nu + ny),), dtype=np.float64, buffer=buffer)
    exps, at = [], 0
    for name, n in shapes:
        u = flat[at : at + n * nu].reshape(n, nu)
        at += n * nu
        y = flat[at : at + n * ny].reshape(n, ny)
        at += n * ny
        u.flags.writeable = False
        y.flags.writeable = False
        exps.append(Experiment(name, u, y))
    return Dataset(list(inputs), list(outputs), ts, exps, source)


def _allowance(buffer: Any, floats: int) -> np.ndarray:
    """The one-float slot after the record in the shared block: the threads each running
    fit may take (:meth:`TaskRunner.map` writes it, the workers' fits read it)."""
    return np.ndarray((1,), dtype=np.float64, buffer=buffer, offset=floats * 8)


def _start_worker(memory_name: str, data_meta: tuple[Any, ...]) -> None:
    """Worker initialiser: map the shared record, limit the thread pools."""
    global _WORKER_DATA, _WORKER_MEMORY
    from multiprocessing import shared_memory

    # (a loky worker shares its parent's resource tracker, so mapping the block here
    # registers nothing new; the parent unlinks it in ``close``)
    _WORKER_MEMORY = shared_memory.SharedMemory(name=memory_name)
    _WORKER_DATA = _views(_WORKER_MEMORY.buf, data_meta)
    _single_threaded()  # for the life of the worker (the environment already says so)
    from blockid.fitting.threads import set_fit_threads, share_threads

    set_fit_threads(1)  # the workers share the cores already: one thread per fit,
    floats = sum(n for _, n in data_meta[4]) * (len(data_meta[0]) + len(data_meta[1]))
    share_threads(_allowance(_WORKER_MEMORY.buf, floats))  # more when cores fall idle
    import numba

    numba.set_num_threads(1)  # outside a fit's kernel_threads, as the environment said


def _call(fn: Callable[[Dataset, Any], Any], item: Any, sizes: dict[str, int]) -> Any:
    """A task in a local worker: ``fn(data, item)`` under the submitter's ``sizes``."""
    assert _WORKER_DATA is not None, "worker started without its data"
    with config_context(**sizes):
        return fn(_WORKER_DATA, item)


#: Set once in a dask worker process by :func:`_cluster_call`: its thread pools limited.
_CLUSTER_LIMITS: Any = None


def _cluster_call(
    fn: Callable[[Dataset, Any], Any], data: Dataset, item: Any, sizes: dict[str, int]
) -> Any:
    """A task on a dask worker: ``fn(data, item)`` under the submitter's ``sizes``, with
    one thread in every pool (set for the life of the worker process, as a local worker's
    initialiser does: a limit lifted when one task ends would change the arithmetic of a
    task running beside it)."""
    global _CLUSTER_LIMITS
    if _CLUSTER_LIMITS is None:
        from blockid.fitting.threads import set_fit_threads

        _CLUSTER_LIMITS = _single_threaded()
        set_fit_threads(1)
    with config_context(**sizes):
        return fn(data, item)


class TaskRunner:
    """Runs ``fn(data, item)`` over items, here or in worker processes (module notes).

    Use as a context manager: the workers and the shared memory live until it exits.

    Parameters
    ----------
    data : Dataset
        The record every call gets.
    jobs : int, optional
        Worker processes; 1 runs everything in this process (default: every core, at
        most :data:`~blockid.workflows.effort.MAX_JOBS`). Ignored with a scheduler.
    scheduler : str or distributed.Client or cluster, optional
        Run the items on this dask cluster instead (module notes). A client given is
        used and left open; one made here from an address or a cluster is closed.
    connect_timeout : float
        Seconds to wait for the scheduler at an address to answer before saying it
        cannot be reached.

    Attributes
    ----------
    jobs : int
        Items run side by side: the worker processes, or the cluster's worker threads.
    local_threads : int
        Threads a fit run here (not on a worker) may take: ``jobs`` without a
        scheduler, else every core of this machine.
    address : str or None
        The dask scheduler's address (None: no cluster).
    """

    def __init__(
        self,
        data: Dataset,
        jobs: int | None = None,
        scheduler: Any = None,
        connect_timeout: float = CONNECT_TIMEOUT,
    ) -> None:
        self.data = data
        self.connect_timeout = connect_timeout
        self.jobs = max(1, int(min(available_cores(), MAX_JOBS) if jobs is None else jobs))
        self.local_threads = self.jobs
        self.scheduler = scheduler
        self.address: str | None = None
        self._pool: Any = None
        self._memory: Any = None
        self._client: Any = None
        self._own_client = False
        self._scattered: Any = None
        self._submitted: list[Any] = []
        self._allowance: np.ndarray | None = None

    def __enter__(self) -> TaskRunner:
        if self.scheduler is not None:
            self._connect()
        elif self.jobs > 1:
            self._start()
        return self

    def _connect(self) -> None:
        try:
            from distributed import Client
        except ImportError:
            raise ImportError(MISSING_DASK) from None
        from blockid.errors import ParameterError

        if isinstance(self.scheduler, Client):
            self._client = self.scheduler
        else:
            try:
                self._client = Client(self.scheduler, timeout=self.connect_timeout)
            except (OSError, TimeoutError, ValueError) as exc:
                raise ParameterError(
                    f"cannot reach the dask scheduler {self.scheduler!r}: {exc}; start one "
                    "(dask scheduler; dask worker ADDRESS) or leave --scheduler out to use "
                    "this machine's cores",
                    parameter="scheduler",
                ) from None
            self._own_client = True
        threads = sum(w["nthreads"] for w in self._client.scheduler_info()["workers"].values())
        if threads < 1:
            self.close()
            raise ParameterError(
                f"the dask cluster at {self.scheduler!r} has no workers; start at least one "
                "(dask worker ADDRESS)",
                parameter="scheduler",
            )
        self.jobs = threads
        self.local_threads = available_cores()
        self.address = str(self._client.scheduler.address)
        self._scattered = self._client.scatter(self.data, broadcast=True, hash=False)

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def _start(self) -> None:
        from multiprocessing import shared_memory

        from loky import ProcessPoolExecutor

        shapes, floats = _layout(self.data)
        self._memory = shared_memory.SharedMemory(create=True, size=(floats + 1) * 8)
        self._allowance = _allowance(self._memory.buf, floats)
        self._allowance[0] = 1.0
        flat = np.ndarray((floats,), dtype=np.float64, buffer=self._memory.buf)
        at = 0
        for e in self.data.experiments:
            for block in (e.u, e.y):
                flat[at : at + block.size] = block.reshape(-1)
                at += block.size
        meta = (
            tuple(self.data.inputs),
            tuple(self.data.outputs),
            self.data.sampling_time,
            self.data.source,
            shapes,
        )
        self._pool = ProcessPoolExecutor(
            max_workers=self.jobs,
            initializer=_start_worker,
            initargs=(self._memory.name, meta),
            env={**WORKER_ENV, "NUMBA_NUM_THREADS": str(self.jobs)},  # the allowance's room
        )

    def close(self) -> None:
        if self._client is not None:
            for future in self._submitted:
                future.cancel()
            self._submitted = []
            if self._scattered is not None:
                self._scattered.release()
                self._scattered = None
            if self._own_client:
                self._client.close()
            self._client = None
        if self._pool is not None:
            for future in self._submitted:  # not started yet (an interrupted map): dropped
                future.cancel()
            self._submitted = []
            self._pool.shutdown(wait=True)
            self._pool = None
        if self._memory is not None:
            self._allowance = None  # (a view on the block: released before it is closed)
            self._memory.close()
            self._memory.unlink()
            self._memory = None

    def map(
        self,
        fn: Callable[[Dataset, Any], Any],
        items: Sequence[Any],
        *,
        done: Callable[[int, Any], None] | None = None,
        deadline: float | None = None,
    ) -> list[Any]:
        """``[fn(data, item) for item in items]``, in the items' order.

        ``done(i, result)`` is called as each result arrives (in any order with
        workers). Items not started by ``deadline`` (:func:`time.monotonic`) give None.
        """
        results: list[Any] = [None] * len(items)
        if self._client is not None:
            return self._map_cluster(fn, items, results, done, deadline)
        if self._pool is None:
            from blockid.fitting.threads import fit_threads

            with _single_threaded(), fit_threads(1):
                for i, item in enumerate(items):
                    if deadline is not None and time.monotonic() > deadline:
                        break
                    results[i] = fn(self.data, item)
                    if done is not None:
                        done(i, results[i])
            return results
        from concurrent.futures import FIRST_COMPLETED, wait

        sizes = get_config()
        futures = {self._pool.submit(_call, fn, item, sizes): i for i, item in enumerate(items)}
        self._submitted = list(futures)
        pending = set(futures)
        self._share(len(pending))
        while pending:
            timeout = None if deadline is None else max(deadline - time.monotonic(), 0.0)
            finished, pending = wait(pending, timeout=timeout, return_when=FIRST_COMPLETED)
            for future in finished:
                if future.cancelled():
                    continue
                i = futures[future]
                results[i] = future.result()
                if done is not None:
                    done(i, results[i])
            self._share(len(pending))
            if deadline is not None and time.monotonic() > deadline:
                for future in pending:
                    future.cancel()  # those already running finish; the rest do not start
                deadline = None  # then wait for the running ones without a timeout
        self._share(0)
        return results

    def _share(self, unfinished: int) -> None:
        """Each running fit may take ``jobs // unfinished`` threads (at least one; one
        again when nothing is left to run)."""
        if self._allowance is not None:
            share = self.jobs // unfinished if unfinished else 1
            self._allowance[0] = float(max(1, share))

    def _map_cluster(
        self,
        fn: Callable[[Dataset, Any], Any],
        items: Sequence[Any],
        results: list[Any],
        done: Callable[[int, Any], None] | None,
        deadline: float | None,
    ) -> list[Any]:
        """:meth:`map` on the dask cluster. At the deadline every unfinished task is
        cancelled (a dask worker cannot be told to finish the running ones only)."""
        import uuid

        from distributed import as_completed

        batch, sizes = uuid.uuid4().hex[:12], get_config()
        futures = {
            self._client.submit(
                _cluster_call,
                fn,
                self._scattered,
                item,
                sizes,
                key=f"blockid-{batch}-{i}",
                pure=False,
            ): i
            for i, item in enumerate(items)
        }
        self._submitted = list(futures)
        running = as_completed(futures)
        while not running.is_empty():
            if deadline is None:
                ready = running.next_batch(block=True)
            else:
                ready = running.next_batch(block=False)
                if not ready:
                    if time.monotonic() > deadline:
                        for future in futures:
                            if not future.done():
                                future.cancel()
                        break
                    time.sleep(0.02)
                    continue
            for future in ready:
                i = futures[future]
                results[i] = future.result()
                if done is not None:
                    done(i, results[i])
        self._submitted = []
        return results
