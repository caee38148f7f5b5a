"""Speed, parallel speed-up and memory of the structure search, ``blockid identify``.

Usage: ``python benchmarks/bench_identify.py [--samples 2000,20000] [--effort E]
[--write-docs]``

For each record length, a Hammerstein-Wiener plant (two-segment polynomial, second-order
linear block, cubic output polynomial) with white output noise at 40 dB is written as a
CSV, and ``blockid identify DATA --input u --output y --effort E --jobs J --json`` runs on
it in a fresh process, as a user would, with ``--jobs 1``, ``--jobs 2`` and
``--scheduler`` on a two-worker dask ``LocalCluster`` (one thread per worker, started
by this script before the run and not counted): the wall
time, the search time ``identify`` reports, the candidates and rejections, the peak
resident memory of the process and of its workers (``ru_maxrss`` of the children: the
largest one, and their sum bounds what they held together) and the chosen structure.
The speed-ups are the ratios of the one-job search time to the two-job and the
cluster's, measured in the same run; the runs must choose the same model (the JSON
documents are compared). The reference is a
single default fit of the true structure (``blockid fit --structure
hammerstein-wiener``) on the same file: what one candidate of the search costs.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _report import machine, write_section

from blockid.blocks import Polynomial, TwoSegmentPolynomial
from blockid.models import HammersteinWiener

_CHILD = (
    "import resource, subprocess, sys; "
    "run = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
    "sys.stderr.write(run.stdout); "
    "print(run.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)
#: ``ru_maxrss`` of the children is the largest of the process tree's members: the
#: ``identify`` process and its workers each hold their own part of it.


def write_record(path: Path, samples: int) -> None:
    rng = np.random.default_rng(0)
    plant = HammersteinWiener(
        "u",
        "y",
        input_block=TwoSegmentPolynomial.from_segments(
            positive=[0.0, 1.0, 0.3], negative=[0.0, 0.6, -0.2]
        ),
        output_block=Polynomial([1.0, 0.2, 0.05], constant=False),
        na=2,
        nb=2,
        nk=1,
        a=[-1.2, 0.35],
        b=[1.0, 0.4],
    )
    u = rng.uniform(-1, 1, samples)
    y = plant.simulate(u[:, None])[:, 0]
    y = y + np.std(y) * 10 ** (-40 / 20) * rng.standard_normal(samples)
    pd.DataFrame({"u": u, "y": y}).to_csv(path, index=False)


def measured(command: list[str]) -> tuple[int, float, float, str]:
    """(exit code, peak resident GB, wall seconds, the command's stdout)."""
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _CHILD, *command], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    code, kb = out.stdout.split()
    return int(code), int(kb) / 1e6, seconds, out.stderr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", default="2000,20000")
    ap.add_argument("--effort", default="standard")
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    blockid = shutil.which("blockid", path=str(Path(sys.executable).parent)) or "blockid"
    rows = []
    from distributed import LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=50)  # fmt: skip
    address = cluster.scheduler_address
    with cluster, tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.samples.split(",")):
            csv = Path(tmp) / f"hw{n}.csv"
            write_record(csv, n)
            base = [blockid, "fit", str(csv), "--input", "u", "--output", "y"]
            fit = base + ["--structure", "hammerstein-wiener", "--na", "2", "--nb", "2"]
            fit += ["--nk", "1", "--quiet", "-o", str(Path(tmp) / "fit.json"), "--force"]
            _, fit_gb, fit_s, _ = measured(fit)
            runs = {}
            for where in (["--jobs", "1"], ["--jobs", "2"], ["--scheduler", address]):
                load = os.getloadavg()[0]
                search = [blockid, "identify", str(csv), "--input", "u", "--output", "y"]
                search += ["--effort", args.effort, *where, "--json", "--quiet"]
                code, gb, seconds, stdout = measured(search)
                doc = json.loads(stdout) if code == 0 else {}
                runs[where[0] + where[1][:1]] = (doc, gb, seconds, load)
            (one, gb1, _, load1), (two, gb2, _, load2), (far, _, _, load3) = runs.values()
            s1, s2, s3 = (d.get("search", {}).get("seconds") for d in (one, two, far))
            same = all(
                json.dumps(one.get("selected"), sort_keys=True)
                == json.dumps(d.get("selected"), sort_keys=True)
                for d in (two, far)
            )
            info = one.get("search", {})
            row = (
                n, fit_s, fit_gb, s1, s2, (s1 / s2) if s1 and s2 else None, s3,
                (s1 / s3) if s1 and s3 else None, info.get("candidates"),
                len(info.get("rejected") or []), gb1, gb2,
                one.get("selected", {}).get("structure", "failed"), same,
                max(load1, load2, load3),
            )  # fmt: skip
            rows.append(row)
            print(row, flush=True)
    lines = [
        "## Structure search: `blockid identify`, one worker, two, and a dask cluster",
        "",
        "`python benchmarks/bench_identify.py` — `blockid identify --effort "
        f"{args.effort}` on a simulated Hammerstein-Wiener record (40 dB output noise) of "
        "each length, in a fresh process, with `--jobs 1`, `--jobs 2` and `--scheduler` on "
        "a two-worker dask `LocalCluster` on the same machine (one thread per worker; "
        "started before the run, not counted): the search time `identify` reports, the "
        "speed-ups over one job (same run), candidates scored "
        "and rejected, peak resident memory (the largest process of the tree: the search "
        "or one worker), the structure chosen and whether all three runs chose the same "
        "model (their `selected` documents equal). Reference: one default fit of the true "
        f"structure on the same file. Machine: {machine()}.",
        "",
        "| samples | one H-W fit s | search s, 1 job | search s, 2 jobs | speed-up | "
        "search s, cluster of 2 | cluster speed-up | candidates | rejected | peak GB, 1 job "
        "| peak GB, 2 jobs | chosen | same model | load average |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---:|",
    ]
    for n, fs, _fg, s1, s2, up, s3, up3, c, r, g1, g2, chosen, same, load in rows:

        def f(v, spec):
            return "-" if v is None else format(v, spec)

        lines.append(
            f"| {n:,} | {fs:.1f} | {f(s1, '.0f')} | {f(s2, '.0f')} | {f(up, '.2f')} | "
            f"{f(s3, '.0f')} | {f(up3, '.2f')} | {c} | "
            f"{r} | {g1:.2f} | {g2:.2f} | {chosen} | {'yes' if same else '**no**'} | "
            f"{load:.1f} |"
        )
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-identify", text)


if __name__ == "__main__":
    main()
