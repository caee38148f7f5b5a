"""Early stopping of the state-space refinements: a held-back tail against none.

Usage::

    .venv/bin/python benchmarks/real/tail_study.py [--only SET ...] [--family NAME ...]
        [--write-docs]

For every shared set (the single-output ones of ``datasets.ALL`` and the multivariable
ones of ``datasets.MIMO``) and three state-space families, ``fit_model`` on the standard
estimation data with every option at its default (the default now holds back the last
20 % of each experiment: ``blockid.defaults.STATE_SPACE_TAIL``), then again with
``tail_fraction=0`` (the refinement to convergence on everything, the default before),
at the same state dimension; each fit's free-run RMSE on the standard test records (as
``run.py`` scores: started from the allowed initial outputs). The ratio of the two, per
set the geometric mean over test records and outputs, and over the sets; and the choice
made **with each set left out in turn** (keep the tail where its geometric mean ratio
over the other sets is below 1). The test records only score; nothing here chooses on
them.

The families: ``state-space`` (linear), ``polynomial-state-space`` at degree 2 with full
monomials (the search's first plan), ``block-state-space`` with a saturation in the loop
(the search's loop plans).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(1, str(Path(__file__).resolve().parent.parent))  # _report

from datasets import ALL, MIMO, REPO, MissingData  # noqa: E402
from run import test_rmse  # noqa: E402

RESULTS = REPO / "benchmarks" / "results" / "tail_study"
DOC = REPO / "docs" / "models.md"
FAMILIES: dict[str, dict[str, Any]] = {
    "state-space": {},
    "polynomial-state-space": {"degree": 2, "monomials": "full"},
    "block-state-space": {"loop_block": "saturation"},
}


def _scores(bench: Any, model: Any) -> list[float]:
    """Every test record's free-run RMSE of every output, in data units."""
    out: list[float] = []
    for rec in bench.tests:
        out += [float(v) for v in test_rmse(model, rec, bench.n_init)[0]]
    return out


def run_one(bench: Any, family: str) -> dict[str, Any]:
    from blockid.fitting.dispatch import fit_model

    options = dict(FAMILIES[family])
    row: dict[str, Any] = {"family": family, "load": os.getloadavg()[0]}
    t0 = time.perf_counter()
    tailed = fit_model(bench.estimation, family, **options)
    row["seconds_tail"] = time.perf_counter() - t0
    nx = int(tailed.model.nx)
    info = tailed.settings.get("refinement", {})
    tail = _scores(bench, tailed.model)
    if info.get("tail_fraction"):
        t0 = time.perf_counter()
        whole = fit_model(bench.estimation, family, **options, nx=nx, tail_fraction=0.0)
        row["seconds_whole"] = time.perf_counter() - t0
        scores = _scores(bench, whole.model)
    else:  # nothing was held back: the same fit (tests/fitting/test_state_space.py)
        scores = tail
    row.update({
        "nx": nx,
        "tail": tail,
        "whole": scores,
        "held_back": info.get("tail_fraction"),
        "start_kept": any("kept the start" in w for w in tailed.settings.get("warnings", [])),
    })  # fmt: skip
    return row


def _ratio(row: dict[str, Any]) -> float:
    a, b = np.asarray(row["tail"]), np.asarray(row["whole"])
    with np.errstate(all="ignore"):
        r = np.log(a / b)
    return float(np.exp(np.mean(r))) if np.all(np.isfinite(r)) else float("nan")


def write_doc(rows: dict[str, dict[str, dict[str, Any]]], titles: dict[str, str]) -> None:
    from _report import machine, write_section

    lines = [
        "#### The study: a held-back tail against none (`benchmarks/real/tail_study.py`)",
        "",
        "Each shared set's standard estimation data, `fit_model` with every option at its "
        "default (a 20 % tail) and again with `tail_fraction=0` at the same state "
        "dimension; the ratio of their free-run RMSE on the standard test records "
        "(geometric mean over records and outputs; below 1: the tail is better). "
        f"Machine: {machine()}.",
        "",
        "| set | " + " | ".join(f"{f} (nx)" for f in FAMILIES) + " |",
        "|---|" + "---:|" * len(FAMILIES),
    ]
    sets = sorted({s for fam in rows.values() for s in fam})
    for s in sets:
        cells = []
        for f in FAMILIES:
            row = rows.get(f, {}).get(s)
            if row is None:
                cells.append("-")
                continue
            mark = " (start)" if row["start_kept"] else (" (whole)" if not row["held_back"] else "")
            cells.append(f"{_ratio(row):.3g} ({row['nx']}){mark}")
        lines.append(f"| {titles.get(s, s)} | " + " | ".join(cells) + " |")
    lines += ["", "| family | sets | geometric mean | worst | best | left out in turn: tail kept |",
              "|---|---:|---:|---:|---:|---|"]  # fmt: skip
    for f in FAMILIES:
        ratios = {s: _ratio(r) for s, r in rows.get(f, {}).items() if np.isfinite(_ratio(r))}
        if not ratios:
            continue
        logs = np.log(np.array(list(ratios.values())))
        kept = sum(
            float(np.mean([np.log(v) for k, v in ratios.items() if k != s])) < 0 for s in ratios
        )
        lines.append(f"| {f} | {len(ratios)} | {np.exp(logs.mean()):.3f} | {logs.max():.3g} | "
                     f"{logs.min():.3g} | {kept} of {len(ratios)} |".replace(
                         f"{logs.max():.3g}", f"{np.exp(logs.max()):.3g}").replace(
                         f"{logs.min():.3g} |", f"{np.exp(logs.min()):.3g} |"))  # fmt: skip
    lines += [
        "",
        "(start): the refinement lowered no tail error and the start was kept; (whole): "
        "100 or more output samples per refined unknown, nothing held back (the two fits "
        "are the same).",
    ]
    write_section("tail-study", "\n".join(lines), DOC)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", default=None)
    p.add_argument("--family", nargs="+", choices=list(FAMILIES), default=list(FAMILIES))
    p.add_argument("--write-docs", action="store_true")
    p.add_argument("--docs-only", action="store_true")
    args = p.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    loaders = {**ALL, **MIMO}
    names = args.only or list(loaders)
    titles: dict[str, str] = {}
    for name in names:
        try:
            bench = loaders[name]()
        except MissingData as exc:
            print(f"{name}: {exc}")
            continue
        titles[name] = bench.title
        if args.docs_only:
            continue
        for family in args.family:
            f = RESULTS / f"{name}__{family}.json"
            try:
                row = run_one(bench, family)
            except Exception as exc:  # noqa: BLE001 - a family that cannot fit a set
                print(name, family, "failed:", str(exc)[:120], flush=True)
                continue
            f.write_text(json.dumps(row, indent=1))
            print(name, family, row["nx"], f"{_ratio(row):.3f}", flush=True)
    if args.write_docs or args.docs_only:
        rows: dict[str, dict[str, dict[str, Any]]] = {}
        for f in sorted(RESULTS.glob("*__*.json")):
            name, family = f.stem.split("__")
            if family in FAMILIES:
                rows.setdefault(family, {})[name] = json.loads(f.read_text())
                if name not in titles:
                    try:
                        titles[name] = loaders[name]().title
                    except MissingData:
                        titles[name] = name
        write_doc(rows, titles)
        print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
