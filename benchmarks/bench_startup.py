"""Start-up of the command line against ``python -c "import numpy"`` and
``python -c "import pandas"`` (issues 9 and 21).

Usage: ``python benchmarks/bench_startup.py [--repeats N] [--write-docs]``

Runs each command in a fresh process ``--repeats`` times (default 7) and keeps the
fastest and the median wall time:

* help: ``blockid --version``, ``blockid --help``, ``blockid fit --help``, against
  ``python -c "import numpy"``; target at most 2.5x;
* commands that fail on their arguments (a missing data file, an unknown ``--effort``,
  a missing model file, an unknown example): they answer before the numerical stack is
  imported, so against ``import numpy`` too; target at most 2.5x;
* a command that reads a small CSV file and fails on a column name: pandas is imported
  but not numba or SciPy, so against ``python -c "import pandas"``; target at most 1.5x;
* ``blockid example-data electrohydraulic`` (simulates the plant: numba, cached).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _report import machine, write_section

TARGETS = {"numpy": 2.5, "pandas": 1.5}


def timings(command: list[str], repeats: int, cwd: Path) -> tuple[float, float]:
    """(fastest, median) wall seconds of ``command`` in fresh processes (any exit)."""
    seconds = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run(
            command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False, cwd=cwd
        )
        seconds.append(time.perf_counter() - t0)
    return min(seconds), statistics.median(seconds)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    blockid = shutil.which("blockid", path=str(Path(sys.executable).parent)) or "blockid"
    py = sys.executable
    # (name, command, reference it is measured against: "numpy", "pandas" or None)
    commands = [
        ('python -c "import numpy"', [py, "-c", "import numpy"], None),
        ('python -c "import pandas"', [py, "-c", "import pandas"], None),
        ("blockid --version", [blockid, "--version"], "numpy"),
        ("blockid --help", [blockid, "--help"], "numpy"),
        ("blockid fit --help", [blockid, "fit", "--help"], "numpy"),
        ("blockid fit missing.csv -u u -y y -o m.json", [blockid, "fit", "missing.csv", "-u",
         "u", "-y", "y", "-o", "m.json"], "numpy"),
        ("blockid identify data.csv -u u -y y --effort huge", [blockid, "identify", "data.csv",
         "-u", "u", "-y", "y", "--effort", "huge"], "numpy"),
        ("blockid simulate missing.json data.csv", [blockid, "simulate", "missing.json",
         "data.csv"], "numpy"),
        ("blockid example-data nope -o x.csv", [blockid, "example-data", "nope", "-o",
         "x.csv"], "numpy"),
        ("blockid fit data.csv -u nope -y y --json (reads the CSV)", [blockid, "fit",
         "data.csv", "-u", "nope", "-y", "y", "--json"], "pandas"),
        ("blockid example-data electrohydraulic -o arm.csv --force", [blockid,
         "example-data", "electrohydraulic", "-o", "arm.csv", "--force"], None),
    ]  # fmt: skip
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "data.csv").write_text("t,u,y\n" + "".join(f"{k},{k},{k}\n" for k in range(200)))
        rows = {name: timings(cmd, args.repeats, folder) for name, cmd, _ in commands}
    reference = {
        "numpy": rows['python -c "import numpy"'][0],
        "pandas": rows['python -c "import pandas"'][0],
    }
    lines = [
        "## Start-up (issues 9 and 21: fast start-up)",
        "",
        f"`python benchmarks/bench_startup.py` — each command in a fresh process, "
        f"{args.repeats} times; fastest and median wall time, and the ratio of the fastest "
        'to the fastest reference of the same run: `python -c "import numpy"` for help and '
        "for commands that fail on their arguments (they answer before NumPy is imported), "
        '`python -c "import pandas"` for a command that reads a small CSV file and then '
        f"fails on a column name (numba and SciPy are not imported). Load average at the "
        f"start {load:.1f}. Machine: {machine()}.",
        "",
        "| command | fastest s | median s | fastest / reference |",
        "|---|---:|---:|---:|",
    ]
    verdicts = []
    for name, _, ref in commands:
        fast, median = rows[name]
        ratio = f"{fast / reference[ref]:.2f} ({ref})" if ref else ""
        lines.append(f"| `{name}` | {fast:.3f} | {median:.3f} | {ratio} |")
        if ref:
            verdicts.append((fast / reference[ref], TARGETS[ref], name))
    missed = [f"`{n}` {r:.2f}x" for r, t, n in verdicts if r > t]
    worst = {ref: max(r for r, t, n in verdicts if t == TARGETS[ref]) for ref in TARGETS}
    lines += [
        "",
        f"Targets: at most {TARGETS['numpy']}x `import numpy` (help, argument errors; worst "
        f"{worst['numpy']:.2f}x) and {TARGETS['pandas']}x `import pandas` (reading a CSV "
        f"file; {worst['pandas']:.2f}x): "
        + ("met." if not missed else f"missed: {', '.join(missed)}."),
    ]
    text = "\n".join(lines)
    print(text)
    if args.write_docs:
        write_section("bench-startup", text)


if __name__ == "__main__":
    main()
