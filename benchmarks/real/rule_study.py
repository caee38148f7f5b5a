"""Which rule should combine the fold scores of ``identify``? Replay saved searches.

Usage::

    .venv/bin/python benchmarks/real/rule_study.py RESULTS_DIR [--only NAME ...]

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

from datasets import ALL  # noqa: E402
from run import test_rmse  # noqa: E402

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
    from blockid.fitting.dispatch import fit_model

    table: dict[str, dict[str, float]] = {}
    for f in sorted(args.results.glob("*.json")):
        r = json.loads(f.read_text())
        if (
            r.get("status") != "ok"
            or "scored" not in r
            or (args.only and r["name"] not in args.only)
        ):
            continue
        bench = ALL[r["name"]]()
        fits: dict[str, float] = {}
        for rule in RULES:
            c = choose(r["scored"], rule)
            key = json.dumps([c["structure"], c["options"]], sort_keys=True)
            if key not in fits:
                try:
                    with np.errstate(all="ignore"):
                        model = fit_model(bench.estimation, c["structure"], **c["options"]).model
                    errs = [test_rmse(model, rec, bench.n_init)[0] * bench.scale
                            for rec in bench.tests]  # fmt: skip
                    fits[key] = float(np.mean(errs))
                except Exception as exc:  # noqa: BLE001 - a study: report and go on
                    print(f"  {rule}: {exc}")
                    fits[key] = float("nan")
            table.setdefault(r["name"], {})[rule] = fits[key]
            label = f"{c['structure']}({', '.join(f'{k}={v}' for k, v in c['options'].items())})"
            print(f"{r['name']:26s} {rule:15s} {fits[key]:10.4g}  {label[:90]}", flush=True)
    print()
    names = sorted(table)
    print("set".ljust(26) + "".join(rule[:12].rjust(13) for rule in RULES))
    for name in names:
        row = table[name]
        best = min(v for v in row.values() if np.isfinite(v))
        print(name.ljust(26) + "".join(f"{row[rule] / best:13.3f}" for rule in RULES))
    ratios = {rule: [table[n][rule] / min(v for v in table[n].values() if np.isfinite(v))
                     for n in names] for rule in RULES}  # fmt: skip
    print("geometric mean".ljust(26)
          + "".join(f"{np.exp(np.mean(np.log(ratios[r]))):13.3f}" for r in RULES))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
