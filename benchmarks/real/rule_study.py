"""Which rule should combine the fold scores of ``identify``? Replay saved searches.

Usage::

    .venv/bin/python benchmarks/real/rule_study.py RESULTS_DIR [--only NAME ...]

(``run.py --rule-study`` does the same on its results folder and keeps the table for
``docs/benchmarks.md``.)

For every set whose search result is saved in ``RESULTS_DIR`` (``run.py --results``),
each rule ranks the candidates that search scored (their per-fold relative errors are in
the file), the winner of each rule is fitted on all estimation data with its own
options, and its free-run RMSE on the standard test records is printed. The pool of
candidates is the one the saved search built (its stages followed its own rule), so
the comparison is of the final choice only; it costs one refit per rule and set.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from datasets import ALL, MIMO  # noqa: E402

TIE = 0.02


def _score(rule: str, rel: np.ndarray, ranks: np.ndarray) -> float:
    if rule == "median":
        return float(np.median(rel))
    if rule == "mean":
        return float(np.mean(rel))
    if rule == "geometric mean":
        return float(np.exp(np.mean(np.log(np.maximum(rel, 1e-300)))))
    if rule == "worst fold":
        return float(np.max(rel))
    if rule == "last fold":  # the single held-back tail of the earlier identify
        return float(rel[-1])
    if rule == "mean rank":
        return float(np.mean(ranks))
    raise ValueError(rule)


RULES = ("median", "mean", "geometric mean", "mean rank", "worst fold", "last fold")


def choose(scored: list[dict], rule: str) -> dict:
    rel = np.array([s["relative"] for s in scored])
    ranks = rel.argsort(axis=0).argsort(axis=0).astype(float)
    values = np.array([_score(rule, r, k) for r, k in zip(rel, ranks, strict=True)])
    best = float(values.min())
    tie = 0.5 if rule == "mean rank" else TIE * best
    near = [i for i in range(len(scored)) if values[i] <= best + tie]
    near.sort(key=lambda i: (scored[i]["flags"] > 0, scored[i]["n_parameters"], values[i]))
    return scored[near[0]]


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("results", type=Path)
    p.add_argument("--only", nargs="+")
    args = p.parse_args()
    from run import rule_study

    names = args.only or sorted(f.stem for f in args.results.glob("*.json"))
    study = rule_study(args.results, [n for n in names if n in {**ALL, **MIMO}])
    print(json.dumps(study["summary"], indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
