"""Speed and memory of the state-space fits (issue 17).

Usage: ``python benchmarks/bench_state_space.py [--samples 100000] [--nfev 20]
[--write-docs]``

A polynomial state-space plant (6 states, one input, one output, monomials of degree 2
and 3 of the states and the input) is simulated with white output noise at 40 dB and
written as a CSV. In a fresh process each, as a user would run them, ``blockid fit
--structure state-space --nx 6`` and ``blockid fit --structure polynomial-state-space
--nx 6 --degree 3 --max-nfev N`` fit it: the wall time and the peak resident memory of
the process (``ru_maxrss``), against the size of the record in memory (inputs and
outputs as float64). The issue's bound: within 1.5 GB for 100 000 samples.
"""

from __future__ import annotations

import argparse
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

from blockid.models.state_space import PolynomialStateSpace, monomial_exponents

_CHILD = (
    "import resource, subprocess, sys; "
    "run = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
    "sys.stderr.write(run.stderr[-2000:]); "
    "print(run.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)


def plant() -> PolynomialStateSpace:
    rng = np.random.default_rng(0)
    nx = 6
    poles = [0.9, 0.8, 0.7, 0.6, -0.5, 0.3]
    A = np.diag(poles) + 0.05 * np.triu(rng.standard_normal((nx, nx)), 1)
    expo = monomial_exponents(nx, 1, 3, "full", constant=True)
    E = 0.01 * rng.standard_normal((nx, expo.shape[0]))
    return PolynomialStateSpace(
        ["u"], ["y"], A, rng.standard_normal((nx, 1)), rng.standard_normal((1, nx)),
        [[0.0]], E, np.zeros((1, expo.shape[0])), expo,
        lower=np.full(nx + 1, -3.0), upper=np.full(nx + 1, 3.0),
    )  # fmt: skip


def measured(command: list[str]) -> tuple[int, float, float]:
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _CHILD, *command], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    code, kb = out.stdout.split()
    if int(code):
        print(out.stderr, file=sys.stderr)
    return int(code), int(kb) / 1e6, seconds


def helper_thread_runs(u: np.ndarray, y: np.ndarray, nfev: int) -> tuple[float, float, bool, float]:
    """The PNLSS fit with the refinement's helper thread off, then on: seconds each,
    whether the parameters are identical, the load average before."""
    from threadpoolctl import threadpool_limits

    from blockid.data import Dataset
    from blockid.fitting import fit_model
    from blockid.fitting.state_space import helper_threads

    data = Dataset.from_arrays(u, y)
    options = {"nx": 6, "degree": 3, "max_nfev": nfev}
    load = os.getloadavg()[0]
    times, params = [], []
    with threadpool_limits(1):
        fit_model(data.select(0, 2000), "polynomial-state-space", **{**options, "max_nfev": 2})
        for on in (False, True):
            with helper_threads(on):
                t0 = time.perf_counter()
                fit = fit_model(data, "polynomial-state-space", **options)
                times.append(time.perf_counter() - t0)
            params.append(fit.model.free_parameters())
            print(f"helper thread {'on' if on else 'off'}: {times[-1]:.1f} s", flush=True)
    return times[0], times[1], bool(np.array_equal(*params)), load


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--nfev", type=int, default=20)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    blockid = shutil.which("blockid", path=str(Path(sys.executable).parent)) or "blockid"
    n = args.samples
    rng = np.random.default_rng(1)
    u = rng.uniform(-1, 1, n)
    y = plant().simulate(u)[:, 0]
    y = y + y.std() * 0.01 * rng.standard_normal(n)
    data_mb = 2 * n * 8 / 1e6
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "pnlss.csv"
        pd.DataFrame({"u": u, "y": y}).to_csv(csv, index=False)
        base = [blockid, "fit", str(csv), "-u", "u", "-y", "y", "--quiet", "--force"]
        runs = {
            "state-space (nx 6)": ["--structure", "state-space", "--nx", "6"],
            f"polynomial-state-space (nx 6, degree 3, {args.nfev} evaluations)": [
                "--structure", "polynomial-state-space", "--nx", "6", "--degree", "3",
                "--max-nfev", str(args.nfev),
            ],
        }  # fmt: skip
        for label, extra in runs.items():
            load = os.getloadavg()[0]
            code, gb, seconds = measured([*base, *extra, "-o", str(Path(tmp) / "m.json")])
            rows.append((label, code, seconds, gb, load))
            print(rows[-1], flush=True)
    helper = helper_thread_runs(u, y, args.nfev)
    lines = [
        "## State-space fits (issue 17)",
        "",
        f"`python benchmarks/bench_state_space.py` — `blockid fit` in a fresh process on a "
        f"simulated polynomial state-space record of {n:,} samples (6 states, monomials of "
        f"degree 2-3, 40 dB output noise; the record is {data_mb:.1f} MB as float64): wall "
        "time (reading the CSV and start-up included) and peak resident memory of the "
        f"process. Machine: {machine()}.",
        "",
        "| fit | exit | wall s | peak GB | load average |",
        "|---|---:|---:|---:|---:|",
    ]
    lines += [f"| {lab} | {c} | {s:.0f} | {g:.2f} | {ld:.1f} |" for lab, c, s, g, ld in rows]
    off, on, same, load = helper
    lines += [
        "",
        "**The helper thread of the refinement** (`blockid.fitting.state_space.helper_thread`: "
        "while the compiled kernel walks the Jacobian over one piece of the record, a second "
        "thread adds the previous piece into the normal equations). The same polynomial "
        f"state-space fit ({args.nfev} evaluations, one BLAS thread) in this process, with "
        "the helper thread off and on, one after the other:",
        "",
        "| helper thread | fit s | speed-up | the same parameters, bit for bit | load average |",
        "|---|---:|---:|---|---:|",
        f"| off | {off:.1f} | 1 | - | {load:.1f} |",
        f"| on | {on:.1f} | {off / on:.2f} | {'yes' if same else '**no**'} | {load:.1f} |",
    ]
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-state-space", text)


if __name__ == "__main__":
    main()
