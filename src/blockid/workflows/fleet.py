"""A fleet of records fitted in parallel on ``dask.distributed``: one model per record.

:func:`fit_fleet` fits every record (one data file each, e.g. the logs of many loops)
with the same structure, method and options, one dask task per record, and writes one
model file per record (``DIR/<file stem>.json``) and a summary table
(``summary.csv`` and ``summary.parquet``, one row per record: file, structure, method,
status, error, seconds, samples and the estimation metrics ``rmse_<output>`` and
``fit_percent_<output>``).

Choices:

- **Where it runs.** A local cluster of ``jobs`` worker processes with one thread each
  (the fits hold the GIL in NumPy and numba code, so processes, not threads), or an
  existing cluster given by its scheduler address; the records must then be readable
  at the same paths on every worker (shared storage; paths are made absolute here).
  Workers read and fit; the model documents come back to this process, which writes
  every file, so only the data needs to be shared.
- **A bad record is a row, never a crashed run.** Anything a record raises (an
  unreadable file, a refused fit, a worker that died) is an ``error`` row with the
  message; the others go on.
- **Reruns.** A record whose model file exists is ``skipped`` (its metrics read back
  from that file) unless ``force``: a rerun after a failure or an interruption fits
  only what is missing. The summary is rewritten every run.
- dask is optional (``pip install 'blockid[fleet]'``) and imported only here, inside
  :func:`fit_fleet`.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from blockid.errors import BlockidError, ParameterError
from blockid.workflows.effort import MAX_JOBS, check_jobs

__all__ = [
    "MISSING_DASK",
    "FleetResult",
    "fit_fleet",
    "fit_record",
    "model_file",
]

#: What to do when dask is not installed (the command line prints it as its error).
MISSING_DASK = "blockid fleet needs dask: pip install 'blockid[fleet]'"

#: The summary's first columns; the metrics per output follow.
COLUMNS = ("file", "structure", "method", "status", "error", "seconds", "n_samples")


def model_file(out_dir: str | Path, path: str | Path) -> Path:
    """The model file of a record: ``out_dir / <stem>.json``."""
    return Path(out_dir) / f"{Path(path).stem}.json"


def _metrics_columns(metrics: dict[str, dict[str, float]] | None, outputs: Sequence[str]):
    metrics = metrics or {}
    return {
        f"{name}_{out}": float(metrics.get(name, {}).get(out, math.nan))
        for out in outputs
        for name in ("rmse", "fit_percent")
    }


def _message(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if isinstance(exc, BlockidError) else f"{type(exc).__name__}: {text}"


def fit_record(
    path: str,
    structure: str,
    inputs: Sequence[str],
    outputs: Sequence[str],
    method: str | None = None,
    options: dict[str, Any] | None = None,
    read_options: dict[str, Any] | None = None,
) -> tuple[dict[str, Any], str | None]:
    """Read and fit one record (a dask task): its summary row and its model file's text
    (None when it failed). Never raises: a failure is a row with status ``error``."""
    from blockid.data import read_data
    from blockid.fitting import fit_model
    from blockid.fitting.threads import fit_threads
    from blockid.models import model_document

    start = time.perf_counter()
    row: dict[str, Any] = {"file": str(path), "structure": structure, "method": method or ""}
    row.update(status="ok", error="", n_samples=0)
    text = None
    try:
        data = read_data([path], inputs, outputs, **(read_options or {}))
        with fit_threads(1):  # the fleet runs one fit per worker thread, side by side
            result = fit_model(data, structure, method=method, **(options or {}))
        doc = model_document(result.model, result.estimation_record())
        text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
        row.update(method=result.method, n_samples=result.n_samples)
        row.update(_metrics_columns(result.estimation_metrics, outputs))
    except Exception as exc:  # any failure of one record is its row, not the run's
        row.update(status="error", error=_message(exc), **_metrics_columns(None, outputs))
        text = None
    row["seconds"] = time.perf_counter() - start
    return row, text


def _skipped(path: str, target: Path, structure: str, method: str, outputs: Sequence[str]) -> dict:
    """The row of a record whose model file exists, its metrics read back from it."""
    row = {"file": path, "structure": structure, "method": method, "status": "skipped"}
    row.update(error="", seconds=0.0, n_samples=0)
    metrics = None
    try:
        record = json.loads(target.read_text()).get("estimation", {})
        row.update(method=record.get("method", ""), n_samples=record.get("n_samples", 0))
        metrics = next(v for k, v in record.items() if k.endswith("_on_estimation_data"))
    except (OSError, ValueError, StopIteration, AttributeError):
        pass  # an unreadable file is still there: skipped, without metrics
    return {**row, **_metrics_columns(metrics, outputs)}


@dataclass(frozen=True)
class FleetResult:
    """The summary of a fleet run: one row per record, in the order given."""

    rows: tuple[dict[str, Any], ...]
    out_dir: Path
    seconds: float  # wall time of the run
    workers: int  # workers of the cluster used

    def counts(self) -> dict[str, int]:
        """Records per status (ok, error, skipped)."""
        return {s: sum(r["status"] == s for r in self.rows) for s in ("ok", "error", "skipped")}

    def to_frame(self) -> Any:
        """The summary table as a pandas DataFrame."""
        import pandas as pd

        return pd.DataFrame(list(self.rows))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN metrics as None)."""
        clean = [
            {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in r.items()}
            for r in self.rows
        ]
        return {
            "out": str(self.out_dir),
            "seconds": self.seconds,
            "workers": self.workers,
            "counts": self.counts(),
            "records": clean,
        }


def fit_fleet(
    paths: Sequence[str | Path],
    out_dir: str | Path,
    structure: str,
    inputs: Sequence[str],
    outputs: Sequence[str],
    *,
    method: str | None = None,
    options: dict[str, Any] | None = None,
    read_options: dict[str, Any] | None = None,
    jobs: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    on_result: Callable[[dict[str, Any]], None] | None = None,
    workers: int | None = None,
) -> FleetResult:
    """Fit every record of ``paths`` in parallel; write the models and the summary.

    Parameters
    ----------
    paths : sequence of paths
        One data file per record (stems must differ: they name the model files).
    out_dir : path
        Folder of the model files and of ``summary.csv`` / ``summary.parquet``.
    structure, method, options
        As in :func:`~blockid.fitting.fit_model`, the same for every record; checked
        before any work starts.
    inputs, outputs, read_options
        As in :func:`~blockid.data.read_data` (``read_options``: ``sampling_time``,
        ``time_column``, ``experiment_column``).
    jobs : int, optional
        Worker processes of the local cluster, one thread each (``identify``'s name and
        default: every core, at most :data:`~blockid.workflows.effort.MAX_JOBS`; more
        is refused, a cluster of your own takes more).
    scheduler : str, optional
        Address of a running cluster's scheduler (``tcp://host:8786``); ``jobs`` is
        then ignored.
    force : bool
        Refit records whose model file exists.
    on_result : callable, optional
        Called with each row as its record finishes (progress).
    workers : int, optional
        The old name of ``jobs`` (a :class:`DeprecationWarning`; not with ``jobs``).

    Raises
    ------
    ImportError
        When dask.distributed is not installed (:data:`MISSING_DASK`).
    ParameterError
        For options the method does not take, no records, or two records of one stem.
    """
    from blockid.fitting.dispatch import resolve_options

    options = dict(options or {})
    # refuse bad options before any work; name the method in every row
    _, method, _ = resolve_options(structure, method, options)
    if workers is not None:
        if jobs is not None:
            raise ParameterError("give jobs, not also workers (its old name)", parameter="workers")
        import warnings

        warnings.warn(
            "fleet(workers=...) is now fleet(jobs=...), identify's name for the same thing",
            DeprecationWarning,
            stacklevel=2,
        )
        jobs = workers
    if check_jobs(jobs) is None:
        from blockid.workflows.parallel import available_cores

        jobs = min(available_cores(), MAX_JOBS)
    files = [str(Path(p).resolve()) for p in paths]
    if not files:
        raise ParameterError("no records to fit")
    stems: dict[str, str] = {}
    for f in files:
        other = stems.setdefault(Path(f).stem, f)
        if other != f:
            raise ParameterError(
                f"{other} and {f} would both be written to {Path(f).stem}.json; give records "
                "with different file names (or run them into different --out folders)"
            )
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ImportError(MISSING_DASK) from None

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows: dict[str, dict[str, Any]] = {}
    todo = []
    for f in files:
        target = model_file(out, f)
        if target.exists() and not force:
            rows[f] = _skipped(f, target, structure, method, outputs)
            if on_result is not None:
                on_result(rows[f])
        else:
            todo.append(f)

    start = time.perf_counter()
    cluster = None
    n_workers = jobs
    if todo:
        if scheduler is None:
            cluster = LocalCluster(
                n_workers=jobs,
                threads_per_worker=1,
                processes=True,
                dashboard_address=":0",  # any free port: clusters side by side
                silence_logs=50,  # logging.CRITICAL: the rows say what failed
            )
        try:
            with Client(scheduler or cluster) as client:
                n_workers = len(client.scheduler_info()["workers"])
                futures = {
                    client.submit(
                        fit_record,
                        f,
                        structure,
                        list(inputs),
                        list(outputs),
                        method,
                        options,
                        read_options,
                        key=f"blockid-fit-{i}-{Path(f).stem}",
                        pure=False,
                    ): f
                    for i, f in enumerate(todo)
                }
                for future in as_completed(futures):
                    f = futures[future]
                    rows[f] = _finish(future, f, out, (structure, method), outputs)
                    if on_result is not None:
                        on_result(rows[f])
        finally:
            if cluster is not None:
                cluster.close()
    result = FleetResult(tuple(rows[f] for f in files), out, time.perf_counter() - start, n_workers)
    _write_summary(result, outputs)
    return result


def _finish(future: Any, path: str, out: Path, fit: tuple, outputs: Sequence[str]) -> dict:
    """The row of a finished task, its model file written (here, not on the worker)."""
    from blockid.data.io import write_text_atomic

    try:
        row, text = future.result()
    except Exception as exc:  # the task itself failed: a worker died, a lost connection
        row = {"file": path, "structure": fit[0], "method": fit[1], "status": "error"}
        text = None
        row.update(error=_message(exc), seconds=math.nan, n_samples=0)
        row.update(_metrics_columns(None, outputs))
    if text is not None:
        try:
            write_text_atomic(text, model_file(out, path), overwrite=True)
        except (OSError, BlockidError) as exc:
            row.update(status="error", error=f"model file not written: {_message(exc)}")
    return row


def _write_summary(result: FleetResult, outputs: Sequence[str]) -> None:
    frame = result.to_frame()
    columns = list(COLUMNS) + [
        f"{name}_{out}" for out in outputs for name in ("rmse", "fit_percent")
    ]
    frame = frame.reindex(columns=columns)
    frame.to_csv(result.out_dir / "summary.csv", index=False)
    frame.to_parquet(result.out_dir / "summary.parquet", index=False)
