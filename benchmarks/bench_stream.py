"""``blockid stream`` end to end: microseconds per sample through standard input and output.

Usage: ``python benchmarks/bench_stream.py [--samples N] [--repeats R] [--write-docs]``

Two cases: a Hammerstein-Wiener record (paper B's plant shape, 15 parameters) learnt by
key-term RLS (forgetting 0.999), and an ARX record with lags of three (``--na 3 --nb 3
--nk 2``, RLS: the default structure, which crashed before issue 21). Each record is
written as CSV and piped into ``blockid stream`` in a fresh process; its JSON lines
are read back through a pipe. The start-up (the same command on the
header alone) is measured separately and subtracted: what remains is the cost per
sample of reading a line, ``update``, writing and flushing its JSON line. The same
record is also run in this process through the library without any I/O
(:func:`~blockid.workflows.stream.stream_identification` on a list of lines, and
``update`` alone), to show where the time goes. Target: under 50 us per sample end to
end (aim: under 20 us). The final estimates are checked against the one-pass offline
fit.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _report import machine, write_section
from bench_online import hw_plant

from blockid.data import Dataset
from blockid.fitting import fit_model
from blockid.fitting.key_term import fit_key_term_rls
from blockid.fitting.online import online_estimator
from blockid.workflows.stream import JsonLines, stream_identification

#: name -> (structure, method, options, command-line flags)
CASES = {
    "Hammerstein-Wiener, key-term RLS (15 parameters)": (
        "hammerstein-wiener", "key-term-rls", {"na": 3, "nb": 3, "nk": 8, "forgetting": 0.999},
        ["--structure", "hammerstein-wiener", "--method", "key-term-rls", "--na", "3",
         "--nb", "3", "--nk", "8", "--forgetting", "0.999"],
    ),
    "ARX na = nb = 3, nk = 2, RLS (6 parameters)": (
        "arx", "rls", {"na": 3, "nb": 3, "nk": 2},
        ["--structure", "arx", "--method", "rls", "--na", "3", "--nb", "3", "--nk", "2"],
    ),
}  # fmt: skip


def record(n: int, structure: str) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    u = rng.uniform(-1.0, 1.0, (n, 1))
    if structure == "arx":
        y = np.convolve(u[:, 0], [0.0, 0.0, 0.5, 0.3, 0.1], "full")[:n, None]
        return u, y + 0.001 * rng.standard_normal((n, 1))
    return u, hw_plant().simulate(u) + 0.001 * rng.standard_normal((n, 1))


def command() -> list[str]:
    """The installed ``blockid stream``."""
    return [str(Path(sys.executable).with_name("blockid")), "stream"]


def piped(cmd: list[str], path: Path, flags: list[str]) -> tuple[tuple[float, float], list[str]]:
    """(wall, CPU) seconds of one run fed ``path`` on stdin, and its output lines. CPU
    is the child's user + system time: what the stream costs, whatever else runs."""
    with path.open("rb") as stdin:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        run = subprocess.run(
            [*cmd, "-u", "u", "-y", "y", *flags], stdin=stdin, capture_output=True, check=True
        )
        seconds = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return (seconds, cpu), run.stdout.decode().splitlines()


def in_process(
    lines: list[str], u: np.ndarray, y: np.ndarray, structure: str, method: str, options: dict
) -> list[tuple[float, float]]:
    """(wall, CPU) seconds of: the stream library with JSON lines (no I/O); ``update``."""
    to_line = JsonLines(["y"])
    clocks = (time.perf_counter, time.process_time)
    t0 = [c() for c in clocks]
    events = stream_identification(lines, structure, ["u"], ["y"], method=method, options=options)
    for event in events:
        to_line(event)
    t_lib = tuple(c() - t for c, t in zip(clocks, t0, strict=True))
    online = online_estimator(structure, method, options, ["u"], ["y"])
    uu, yy = u.tolist(), y.tolist()
    t0 = [c() for c in clocks]
    for a, b in zip(uu, yy, strict=True):
        online.update(a, b)
    t_update = tuple(c() - t for c, t in zip(clocks, t0, strict=True))
    return [t_lib, t_update]


def best(times: list[tuple[float, float]]) -> tuple[float, float]:
    """Best wall and best CPU time of several runs."""
    return min(t[0] for t in times), min(t[1] for t in times)


def measure(name: str, n: int, repeats: int) -> tuple[list[str], float]:
    """The table rows of one case and its largest end-to-end CPU us per sample."""
    structure, method, options, flags = CASES[name]
    u, y = record(n, structure)
    text = "u,y\n" + "".join(
        f"{a!r},{b!r}\n" for a, b in zip(u[:, 0].tolist(), y[:, 0].tolist(), strict=True)
    )
    cmd = command()
    with tempfile.TemporaryDirectory() as tmp:
        full, empty = Path(tmp) / "record.csv", Path(tmp) / "header.csv"
        full.write_text(text)
        empty.write_text("u,y\n")
        piped(cmd, empty, flags)  # warm the numba cache and the file cache
        t_start = best([piped(cmd, empty, flags)[0] for _ in range(repeats)])
        runs = [piped(cmd, full, flags) for _ in range(repeats)]
    t_full = best([r[0] for r in runs])
    lines = runs[0][1]
    final = json.loads(lines[-1])
    assert final["n_samples"] == n and len(lines) == n + 1
    inside = [in_process(text.splitlines(), u, y, structure, method, options)
              for _ in range(repeats)]  # fmt: skip
    t_lib, t_update = best([i[0] for i in inside]), best([i[1] for i in inside])

    data = Dataset.from_arrays(u, y, inputs=["u"], outputs=["y"])
    if structure == "arx":
        offline = fit_model(data, "arx", method=method, center=False, **options).model
    else:
        offline = fit_key_term_rls(data, structure, passes=1, normalize=False, **options).model
    flat = lambda p: np.concatenate([np.ravel(v) for v in _leaves(p)])  # noqa: E731
    agree = float(np.max(np.abs(flat(final["parameters"]) - flat(offline.to_dict()["parameters"]))))

    def us(t: tuple[float, float], minus: tuple[float, float] = (0.0, 0.0)) -> str:
        return f"{(t[0] - minus[0]) / n * 1e6:.1f} | {(t[1] - minus[1]) / n * 1e6:.1f}"

    rows = [
        f"| {name} | start-up (header only) | {t_start[0]:.2f} | | |",
        f"| | end to end, stdin to stdout | {t_full[0]:.2f} | {us(t_full, t_start)} |",
        f"| | in process: read + `update` + JSON line, no I/O | {t_lib[0]:.2f} | {us(t_lib)} |",
        f"| | in process: `update` alone | {t_update[0]:.2f} | {us(t_update)} |",
        f"| | final estimates vs one-pass offline fit: max abs difference {agree:.1e} | | | |",
    ]
    return rows, (t_full[1] - t_start[1]) / n * 1e6


def _leaves(tree: object) -> list:
    if isinstance(tree, dict):
        return [x for v in tree.values() for x in _leaves(v)]
    if isinstance(tree, list) and tree and isinstance(tree[0], list | dict):
        return [x for v in tree for x in _leaves(v)]
    return [np.asarray(tree, dtype=float)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    N = args.samples
    load = os.getloadavg()[0]
    table, worst = [], 0.0
    for name in CASES:
        rows, cpu = measure(name, N, args.repeats)
        table += rows
        worst = max(worst, cpu)
    lines_md = [
        "## Streaming identification (issues 9 and 21: blockid stream)",
        "",
        f"`python benchmarks/bench_stream.py` — {N:,}-sample records as CSV piped into "
        "`blockid stream` in a fresh process, its JSON lines (one per sample, flushed) read "
        f"back through a pipe; best of {args.repeats}. Start-up (the same command on the "
        "header line alone) is subtracted. Wall time and CPU time (user + system of the "
        f"stream's process). Load average at the start {load:.1f} on {os.cpu_count()} "
        f"cores. Machine: {machine()}.",
        "",
        "| case | what | wall s | wall us/sample | CPU us/sample |",
        "|---|---|---:|---:|---:|",
        *table,
        "",
        f"Target: under 50 us per sample end to end (aim: under 20 us): "
        f"{'met' if worst < 50 else 'missed'} (worst CPU {worst:.1f} us/sample). What the "
        "stream adds to `update` is parsing the CSV line (the `csv` module), building the "
        "JSON line (no `json.dumps` on the per-sample path) and one `write` and `flush` per "
        "sample (a system call each: a plant waits for its answer).",
    ]
    report = "\n".join(lines_md)
    print(report)
    if args.write_docs:
        write_section("bench-stream", report)


if __name__ == "__main__":
    main()
