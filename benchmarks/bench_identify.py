"""Speed and memory of the structure search, ``blockid identify`` (issue 10).

Usage: ``python benchmarks/bench_identify.py [--samples 10000,100000] [--budget S]
[--write-docs]``

For each record length, a Hammerstein-Wiener plant (two-segment polynomial, second-order
linear block, cubic output polynomial) with white output noise at 40 dB is written as a
CSV, and ``blockid identify DATA --input u --output y --budget S --json -o model.json``
runs on it in a fresh process, as a user would: the wall time, the search time
``identify`` reports, the number of candidates and rejections, the peak resident memory
of the process (``ru_maxrss``) and the chosen structure. The reference measured in the
same run is a single default fit of the true structure (``blockid fit --structure
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
    ap.add_argument("--samples", default="10000,100000")
    ap.add_argument("--budget", type=float, default=300.0)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    blockid = shutil.which("blockid", path=str(Path(sys.executable).parent)) or "blockid"
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.samples.split(",")):
            csv = Path(tmp) / f"hw{n}.csv"
            write_record(csv, n)
            base = [blockid, "fit", str(csv), "--input", "u", "--output", "y"]
            fit = base + ["--structure", "hammerstein-wiener", "--na", "2", "--nb", "2"]
            fit += ["--nk", "1", "--quiet", "-o", str(Path(tmp) / "fit.json"), "--force"]
            _, fit_gb, fit_s, _ = measured(fit)
            load = os.getloadavg()[0]
            search = [blockid, "identify", str(csv), "--input", "u", "--output", "y"]
            search += ["--budget", str(args.budget), "--json", "--quiet"]
            search += ["-o", str(Path(tmp) / f"id{n}.json"), "--force"]
            code, gb, seconds, stdout = measured(search)
            doc = json.loads(stdout) if code == 0 else {}
            info = doc.get("search", {})
            selected = doc.get("selected", {})
            structure = selected.get("structure", f"exit {code}")
            rejected = len(info.get("rejected") or [])
            searched = info.get("seconds")
            row = (n, fit_s, fit_gb, seconds, searched, info.get("candidates"), rejected, gb)
            rows.append((*row, structure, load))
            print(rows[-1], flush=True)
    lines = [
        "## Structure search (issue 10: blockid identify)",
        "",
        "`python benchmarks/bench_identify.py` — `blockid identify` on a simulated "
        "Hammerstein-Wiener record (40 dB output noise) of each length, budget "
        f"{args.budget:g} s, in a fresh process: wall time (start-up and the final refit "
        "included), the search time `identify` reports, candidates scored and rejected, "
        "peak resident memory of the process, the structure chosen. Reference in the same "
        "run: one default fit of the true structure on the same file. Machine: "
        f"{machine()}.",
        "",
        "| samples | one H-W fit s | one H-W fit GB | identify wall s | search s | candidates "
        "| rejected | identify peak GB | chosen | load average |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for n, fs, fg, s, ss, c, r, g, chosen, load in rows:
        shown = "-" if ss is None else f"{ss:.0f}"
        lines.append(
            f"| {n:,} | {fs:.1f} | {fg:.2f} | {s:.0f} | {shown} | {c} | {r} | {g:.2f} | "
            f"{chosen} | {load:.1f} |"
        )
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-identify", text)


if __name__ == "__main__":
    main()
