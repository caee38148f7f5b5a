"""``blockid fleet``: records per second on 1 and 2 dask workers, and a 200-record run.

Usage: ``python benchmarks/bench_fleet.py [--records N] [--big N] [--samples N]
[--structure NAME] [--write-docs]``

Generates Hammerstein records (a two-segment polynomial then a linear block, with
noise), one CSV each, and fits them with the default method (simulation error) through
:func:`~blockid.workflows.fleet.fit_fleet`: on a local cluster of 1 worker, then of 2
workers (processes, one thread each), each cluster started and warmed (imports, the
numba cache) before the clock starts; the start-up of a cluster is reported apart (it
is what one ``blockid fleet`` call pays on top). Then a run of ``--big`` records on 2
workers. Target: at least 1.5x on 2 workers. Every run uses ``force`` (all records
refitted).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _report import machine, write_section

from blockid.blocks import TwoSegmentPolynomial
from blockid.models import Hammerstein
from blockid.workflows.fleet import fit_fleet

ORDERS = {"na": 2, "nb": 2, "nk": 1}


def write_records(folder: Path, count: int, samples: int) -> list[Path]:
    n1 = TwoSegmentPolynomial.from_segments(positive=[0, 1.0, 0.3], negative=[0, 0.6, -0.2])
    paths = []
    for i in range(count):
        rng = np.random.default_rng(i)
        plant = Hammerstein(
            "u",
            "y",
            input_block=n1,
            na=2,
            nb=2,
            nk=1,
            a=[-1.2 + 0.01 * rng.random(), 0.35],
            b=[1.0, 0.4],
        )
        u = rng.uniform(-1, 1, samples)
        y = plant.simulate(u[:, None])[:, 0] + 0.01 * rng.standard_normal(samples)
        path = folder / f"loop{i:04d}.csv"
        pd.DataFrame({"u": u, "y": y}).to_csv(path, index=False)
        paths.append(path)
    return paths


def _warm() -> None:
    import blockid.fitting.simulation_error  # noqa: F401  (imports and numba cache)


def _cpu() -> float:
    """User + system seconds of this worker process so far."""
    import psutil  # a dependency of distributed

    times = psutil.Process().cpu_times()
    return times.user + times.system


def timed_run(paths, out, workers, structure):
    """(cluster start-up s, fit s, CPU s of the workers, counts) of one fleet run on its
    own warmed cluster."""
    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    with (
        LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        Client(cluster) as client,
    ):
        client.run(_warm)
        startup = time.perf_counter() - t0
        fit_fleet(
            paths[:2],
            out,
            structure,
            ["u"],
            ["y"],
            options=ORDERS,
            scheduler=cluster.scheduler_address,
            force=True,
        )  # compile on every worker
        cpu0 = sum(client.run(_cpu).values())
        t0 = time.perf_counter()
        result = fit_fleet(
            paths,
            out,
            structure,
            ["u"],
            ["y"],
            options=ORDERS,
            scheduler=cluster.scheduler_address,
            force=True,
        )
        seconds = time.perf_counter() - t0
        cpu = sum(client.run(_cpu).values()) - cpu0
    return startup, seconds, cpu, result.counts()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=20)
    ap.add_argument("--big", type=int, default=200)
    ap.add_argument("--samples", type=int, default=10_000)
    ap.add_argument("--structure", default="hammerstein")
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        paths = write_records(folder, max(args.records, args.big), args.samples)
        small = paths[: args.records]
        rows = {}
        for workers in (1, 2):
            load = os.getloadavg()[0]
            rows[workers] = (
                *timed_run(small, folder / f"out{workers}", workers, args.structure),
                load,
            )
            print(workers, rows[workers], flush=True)
        load = os.getloadavg()[0]
        big = (*timed_run(paths[: args.big], folder / "big", 2, args.structure), load)
        print("big", big, flush=True)

    text = report(args.structure, args.samples, args.records, args.big, rows, big)
    print(text)
    if args.write_docs:
        write_section("bench-fleet", text)


def report(structure, samples, records, n_big, rows, big) -> str:
    """The docs section from the measured (start-up, wall, CPU, counts, load) tuples."""
    speedup = rows[1][1] / rows[2][1]
    lines = [
        "## Fleets on dask (issue 9: blockid fleet)",
        "",
        f"`python benchmarks/bench_fleet.py` — {structure} records of {samples:,} "
        "samples (CSV), each fitted by the default method (simulation error) as one dask "
        "task; a local cluster of worker processes with one thread each, started and "
        "warmed (imports, numba cache) before the clock starts. 'Worker CPU' is the user + "
        "system time the worker processes used during the run, and 'cores used' that "
        "divided by the wall time: how many cores the workers got together; the load average "
        "is the machine's 1-minute load when the run started (other jobs included). "
        f"Machine: {machine()}.",
        "",
        "| records | workers | cluster start-up s | wall s | records/s | worker CPU s "
        "| cores used | load average | result |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for n, workers, (startup, seconds, cpu, counts, load) in (
        (records, 1, rows[1]),
        (records, 2, rows[2]),
        (n_big, 2, big),
    ):
        lines.append(
            f"| {n} | {workers} | {startup:.1f} | {seconds:.2f} | "
            f"{n / seconds:.1f} | {cpu:.2f} | {cpu / seconds:.2f} | {load:.1f} | "
            f"{counts['ok']} ok |"
        )
    # what the work allows when the cores are free: 2 workers x the CPU per record ratio
    allowed = 2 * rows[1][2] / rows[2][2]
    lines += [
        "",
        f"Speed-up on 2 workers over 1, measured: **{speedup:.2f}x** (target >= 1.5x). "
        f"CPU per record: {rows[1][2] / records * 1e3:.0f} ms on 1 worker, "
        f"{rows[2][2] / records * 1e3:.0f} ms on 2 (scheduling, transfer and reading "
        f"included), so with two free cores the speed-up would be about {allowed:.2f}x. "
        "'Cores used' shows why the measured one is lower when the machine is shared: "
        "the workers together got what the other jobs left.",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
