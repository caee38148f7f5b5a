"""Can ``identify`` race its block structures? Replay saved searches, each set left out
in turn.

Usage::

    .venv/bin/python benchmarks/real/race_study.py RESULTS_DIR [--out FILE]

A race scores every candidate of the structures stage on the first fold only and
carries the best ``1 / eta`` of them (at least ``RACE_MIN``) on to the other folds; the
rest are never scored on those. The leaders' scores are then exactly what the unraced
stage gives them (each fold's fit is the same), so a race changes ``identify``'s answer
only when a candidate that the full stage ranks among its best few is not carried on:
the later stages (finalists, the nonlinearity's growth, the choice against the linear
model) start from the stage's best candidates.

For every set whose unraced search is saved in ``RESULTS_DIR`` (``run.py --results``,
every candidate's fold errors in ``scored``), this takes the structures stage's
candidates scored on every fold, ranks them by their score (the geometric mean over the
folds, as ``identify`` does) and by their first fold alone, and asks, for each ``eta``
of :data:`ETAS`, whether the race keeps the full ranking's best ``TOP`` (the finalists
and the spare the stages after draw on). It does so for long records (``LONG_RECORD``
samples or more), which the race is for, and for the shorter ones to show why it is
not run there.

The choice of ``eta`` is scored **with each set left out in turn**: the largest ``eta``
(the cheapest race) that keeps the top on every other long set is the one that set
gets, and the study says whether it keeps the left-out set's top too.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

#: The fractions raced: the best ``1 / eta`` carried on.
ETAS = (2, 3, 4, 6, 8)
#: The full ranking's best this many must be carried on (the standard effort's three
#: finalists and two to spare).
TOP = 5
STAGE = "structures"


def _ranks(entries: list[dict[str, Any]]) -> tuple[int, int]:
    """The number of candidates, and the worst first-fold rank (0: the best) among the
    full ranking's best ``TOP``."""
    rel = [np.asarray(e["relative"], dtype=float) for e in entries]
    full = sorted(range(len(rel)), key=lambda i: float(np.mean(np.log(rel[i]))))
    first = sorted(range(len(rel)), key=lambda i: float(rel[i][0]))
    where = {i: r for r, i in enumerate(first)}
    return len(rel), max(where[i] for i in full[:TOP])


def _kept(n: int, eta: int, least: int) -> int:
    return max(least, math.ceil(n / eta))


def study(results: Path) -> dict[str, Any]:
    from blockid.workflows.effort import LONG_RECORD
    from blockid.workflows.identify import RACE_MIN

    sets: dict[str, dict[str, Any]] = {}
    for f in sorted(results.glob("*.json")):
        r = json.loads(f.read_text())
        if r.get("status") != "ok" or "scored" not in r:
            continue
        entries = [
            e
            for e in r["scored"]
            if e.get("stage") == STAGE
            and len(e.get("relative") or []) >= 2
            and all(math.isfinite(v) for v in e["relative"])
        ]
        if len(entries) < 2 * TOP:
            continue
        n, worst = _ranks(entries)
        sets[r["name"]] = {
            "samples": r["estimation_samples"],
            "long": r["estimation_samples"] >= LONG_RECORD,
            "candidates": n,
            "worst_first_fold_rank_of_top": worst,
            "keeps_top": {eta: worst < _kept(n, eta, RACE_MIN) for eta in ETAS},
        }
    long = [name for name, s in sets.items() if s["long"]]
    loso = {}
    for left in long:
        others = [n for n in long if n != left]
        safe = [eta for eta in ETAS if all(sets[n]["keeps_top"][eta] for n in others)]
        eta = max(safe) if safe else 1
        loso[left] = {"eta": eta, "keeps_top": eta == 1 or sets[left]["keeps_top"][eta]}
    return {"top": TOP, "race_min": RACE_MIN, "etas": list(ETAS), "sets": sets, "loso": loso}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("results", type=Path)
    p.add_argument("--out", type=Path)
    args = p.parse_args(argv)
    out = study(args.results)
    print(f"{'set':28s} {'samples':>8s} {'cands':>5s} {'worst rank':>10s}  " +
          "  ".join(f"eta={e}" for e in ETAS))  # fmt: skip
    for name, s in out["sets"].items():
        keeps = "  ".join(f"{'yes' if s['keeps_top'][e] else 'NO':>5s}" for e in ETAS)
        worst, short = s["worst_first_fold_rank_of_top"], "" if s["long"] else "  (short)"
        print(f"{name:28s} {s['samples']:8d} {s['candidates']:5d} {worst:10d}  {keeps}{short}")
    for name, v in out["loso"].items():
        print(f"left out {name}: eta {v['eta']} chosen on the others; keeps its top: "
              f"{v['keeps_top']}")  # fmt: skip
    if args.out:
        args.out.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
