"""Speed, parallel speed-up and memory of the structure search, ``blockid identify``.

Usage: ``python benchmarks/bench_identify.py [--samples 2000,20000] [--effort E]
[--write-docs]``

For each record length, a Hammerstein-Wiener plant (two-segment polynomial, second-order
linear block, cubic output polynomial) with white output noise at 40 dB is written as a
CSV, and ``blockid identify DATA --input u --output y --effort E --jobs J --json`` runs on
it in a fresh process, as a user would, with ``--jobs 1`` and ``--jobs 2``: the wall
time, the search time ``identify`` reports, the candidates and rejections, the peak
resident memory of the process and of its workers (``ru_maxrss`` of the children: the
largest one, and their sum bounds what they held together) and the chosen structure.
The speed-up is the ratio of the two search times, measured in the same run; the two
runs must choose the same model (the JSON documents are compared). The reference is a
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
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.samples.split(",")):
            csv = Path(tmp) / f"hw{n}.csv"
            write_record(csv, n)
            base = [blockid, "fit", str(csv), "--input", "u", "--output", "y"]
            fit = base + ["--structure", "hammerstein-wiener", "--na", "2", "--nb", "2"]
            fit += ["--nk", "1", "--quiet", "-o", str(Path(tmp) / "fit.json"), "--force"]
            _, fit_gb, fit_s, _ = measured(fit)
            runs = {}
            for jobs in (1, 2):
                load = os.getloadavg()[0]
                search = [blockid, "identify", str(csv), "--input", "u", "--output", "y"]
                search += ["--effort", args.effort, "--jobs", str(jobs), "--json", "--quiet"]
                code, gb, seconds, stdout = measured(search)
                doc = json.loads(stdout) if code == 0 else {}
                runs[jobs] = (doc, gb, seconds, load)
            (one, gb1, _, load1), (two, gb2, _, load2) = runs[1], runs[2]
            s1, s2 = one.get("search", {}).get("seconds"), two.get("search", {}).get("seconds")
            same = json.dumps(one.get("selected"), sort_keys=True) == json.dumps(
                two.get("selected"), sort_keys=True
            )
            info = one.get("search", {})
            row = (
                n, fit_s, fit_gb, s1, s2, (s1 / s2) if s1 and s2 else None, info.get("candidates"),
                len(info.get("rejected") or []), gb1, gb2,
                one.get("selected", {}).get("structure", "failed"), same, max(load1, load2),
            )  # fmt: skip
            rows.append(row)
            print(row, flush=True)
    lines = [
        "## Structure search: `blockid identify`, one worker and two",
        "",
        "`python benchmarks/bench_identify.py` — `blockid identify --effort "
        f"{args.effort}` on a simulated Hammerstein-Wiener record (40 dB output noise) of "
        "each length, in a fresh process, with `--jobs 1` and `--jobs 2`: the search time "
        "`identify` reports, the speed-up (ratio of the two, same run), candidates scored "
        "and rejected, peak resident memory (the largest process of the tree: the search "
        "or one worker), the structure chosen and whether both runs chose the same model "
        "(their `selected` documents equal). Reference: one default fit of the true "
        f"structure on the same file. Machine: {machine()}.",
        "",
        "| samples | one H-W fit s | search s, 1 job | search s, 2 jobs | speed-up | "
        "candidates | rejected | peak GB, 1 job | peak GB, 2 jobs | chosen | same model "
        "| load average |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---:|",
    ]
    for n, fs, _fg, s1, s2, up, c, r, g1, g2, chosen, same, load in rows:

        def f(v, spec):
            return "-" if v is None else format(v, spec)

        lines.append(
            f"| {n:,} | {fs:.1f} | {f(s1, '.0f')} | {f(s2, '.0f')} | {f(up, '.2f')} | {c} | "
            f"{r} | {g1:.2f} | {g2:.2f} | {chosen} | {'yes' if same else '**no**'} | "
            f"{load:.1f} |"
        )
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-identify", text)


if __name__ == "__main__":
    main()
