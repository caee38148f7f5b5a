"""Start-up of the command line against ``python -c "import numpy"`` (issue 9).

Usage: ``python benchmarks/bench_startup.py [--repeats N] [--write-docs]``

Runs each command in a fresh process ``--repeats`` times (default 7) and keeps the
fastest and the median wall time: ``blockid --version``, ``blockid --help``,
``blockid fit --help`` and the reference measured in the same run,
``python -c "import numpy"``. Target: ``--version`` and ``--help`` at most 2.5x the
reference.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from _report import machine, write_section

TARGET = 2.5


def timings(command: list[str], repeats: int) -> tuple[float, float]:
    """(fastest, median) wall seconds of ``command`` in fresh processes."""
    seconds = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        seconds.append(time.perf_counter() - t0)
    return min(seconds), statistics.median(seconds)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    blockid = shutil.which("blockid", path=str(Path(sys.executable).parent)) or "blockid"
    commands = {
        'python -c "import numpy"': [sys.executable, "-c", "import numpy"],
        "blockid --version": [blockid, "--version"],
        "blockid --help": [blockid, "--help"],
        "blockid fit --help": [blockid, "fit", "--help"],
    }
    load = os.getloadavg()[0]
    rows = {name: timings(command, args.repeats) for name, command in commands.items()}
    reference = rows['python -c "import numpy"']
    lines = [
        "## Start-up (issue 9: fast start-up)",
        "",
        f"`python benchmarks/bench_startup.py` — each command in a fresh process, "
        f"{args.repeats} times; fastest and median wall time, and the ratio of the fastest "
        f'to the fastest `python -c "import numpy"` of the same run. Load average at the '
        f"start {load:.1f}. Machine: {machine()}.",
        "",
        "| command | fastest s | median s | fastest / import numpy |",
        "|---|---:|---:|---:|",
    ]
    for name, (fast, median) in rows.items():
        lines.append(f"| `{name}` | {fast:.3f} | {median:.3f} | {fast / reference[0]:.2f} |")
    worst = max(rows[n][0] for n in ("blockid --version", "blockid --help")) / reference[0]
    verdict = "met" if worst <= TARGET else "missed"
    lines += ["", f"Target: `--version` and `--help` at most {TARGET}x: {verdict} ({worst:.2f}x)."]
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-startup", text)


if __name__ == "__main__":
    main()
