"""When should ``identify`` keep a model beyond linear? Replay saved searches, each set
left out in turn.

Usage::

    .venv/bin/python benchmarks/real/linear_rule_study.py RESULTS_DIR [--out FILE]

``identify`` chooses the best-scored candidate over the best linear one only when the
mean over the folds of the log of their errors' ratio lies below ``-c`` standard
errors (``blockid.workflows.identify.LINEAR_MARGIN`` is ``c``). For every set whose
search is saved in ``RESULTS_DIR`` (``run.py --results``) with that comparison recorded
(``search.beyond_linear``: the best candidate was beyond linear and a linear one was
scored on the same folds), both candidates are fitted on all estimation data with their
own options and simulated free-run on the standard test records; a margin ``c`` picks
one of them. The loss of a pick on a set is the log of its test error over the better
of the two.

Each margin of :data:`MARGINS` is scored on all sets, and the choice of the margin is
scored **with each set left out in turn**: the margin with the least loss on the other
sets (ties: the largest, the most cautious) is the one that set gets. A margin chosen on
all sets and scored on the same ones would say little about a record none of them is.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from datasets import ALL, MIMO  # noqa: E402

#: The margins compared, in standard errors (1: the one-standard-error rule).
MARGINS = (0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0)


def _tuples(v: Any) -> Any:
    return tuple(_tuples(x) for x in v) if isinstance(v, list) else v


def _label(entry: dict[str, Any]) -> str:
    from blockid.workflows.search_space import Candidate

    options = {k: _tuples(v) for k, v in entry["options"].items()}
    return Candidate(entry["structure"], options).label


def _test_error(name: str, entry: dict[str, Any]) -> float:
    """``entry``'s candidate fitted on all estimation data: its mean free-run test RMSE
    over the set's test records and outputs, relative to the estimation output's spread
    (inf when the fit fails or the simulation diverges)."""
    from run import test_rmse

    from blockid.fitting.dispatch import fit_model

    bench = {**ALL, **MIMO}[name]()
    try:
        with np.errstate(all="ignore"):
            model = fit_model(bench.estimation, entry["structure"], **entry["options"]).model
        errs = [v for rec in bench.tests for v in test_rmse(model, rec, bench.n_init)[0]]
    except Exception:  # noqa: BLE001 - a study: a failed fit counts as inf
        return float("inf")
    return float(np.mean(errs))


def refined(
    name: str, entries: list[dict[str, Any]], folds: int, nfev: int | None = None
) -> dict[str, Any]:
    """Both candidates scored again on ``folds`` folds of the estimation data (each fitted
    on the others, simulated free-run over the held-back one from the search's
    ``n_init``): the paired mean log ratio of their fold errors and its standard error."""
    from blockid.data.folds import fold_plan
    from blockid.workflows.identify import _fit_and_score, _Task
    from blockid.workflows.search_space import Candidate

    data = {**ALL, **MIMO}[name]().estimation
    first = fold_plan(data, 4)  # the search's plan at the standard effort: its n_init
    shortest = min(s.n_samples for f in first.folds for s in f.test)
    n_init = int(min(50, max(10, shortest // 10)))
    plan = fold_plan(data, folds)
    logs = []
    for e in entries:
        options = {k: _tuples(v) for k, v in e["options"].items()}
        if nfev and "max_nfev" in options:
            options["max_nfev"] = max(options["max_nfev"], nfev)
        cand = Candidate(e["structure"], options)
        scores = [_fit_and_score(data, _Task(cand, f, None, n_init)) for f in plan.folds]
        if any(s.reason for s in scores):
            return {"folds": len(plan), "failed": e["structure"]}
        logs.append(np.log([s.relative for s in scores]))
    d = logs[0] - logs[1]
    return {
        "folds": len(plan),
        "mean_log_ratio": float(np.mean(d)),
        "standard_error": float(np.std(d, ddof=1) / np.sqrt(len(d))),
        "folds_won": int(np.sum(d < 0)),
    }


def decisions(
    results: Path, refine: int | None = None, nfev: int | None = None
) -> list[dict[str, Any]]:
    """Per set with a recorded comparison: its numbers and both picks' test errors
    (with ``refine``, the comparison on that many folds too)."""
    rows = []
    for f in sorted(results.glob("*.json")):
        r = json.loads(f.read_text())
        info = (r.get("search") or {}).get("beyond_linear")
        if r.get("status") != "ok" or not info or r["name"] not in {**ALL, **MIMO}:
            continue
        by_label = {_label(e): e for e in r["scored"]}
        best, linear = by_label.get(info["best"]), by_label.get(info["linear"])
        if best is None or linear is None:
            print(f"{r['name']}: candidates not found in the saved scores", flush=True)
            continue
        row = {
            "name": r["name"],
            "title": r["title"],
            "best": info["best"],
            "linear": info["linear"],
            "mean_log_ratio": info["mean_log_ratio"],
            "standard_error": info["standard_error"],
            "folds_won": info["folds_won"],
            "folds": info["folds"],
            "t": info["mean_log_ratio"] / max(info["standard_error"], 1e-300),
        }
        if refine:
            row["refined"] = refined(r["name"], [best, linear], refine, nfev)
        if all(_keeps(row, c) for c in MARGINS) and not refine:
            row.update(best_test=None, linear_test=None)  # every margin agrees: no refit
        else:
            row.update(best_test=_test_error(r["name"], best),
                       linear_test=_test_error(r["name"], linear))  # fmt: skip
        shown = ("name", "t", "best_test", "linear_test", "refined")
        print(json.dumps({k: row.get(k) for k in shown}), flush=True)
        rows.append(row)
    return rows


def _keeps(row: dict[str, Any], margin: float) -> bool:
    """Whether ``margin`` keeps the model beyond linear."""
    return row["mean_log_ratio"] < -margin * row["standard_error"]


def _loss(row: dict[str, Any], margin: float) -> float:
    """log(test error of the pick / the better test error); 0 where every margin agrees."""
    if row["best_test"] is None:
        return 0.0
    pick = row["best_test"] if _keeps(row, margin) else row["linear_test"]
    better = min(row["best_test"], row["linear_test"])
    if not np.isfinite(pick):
        return float(np.log(1e3))  # a diverging pick: counted as 1000 times worse
    return float(np.log(pick / better))


def study(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Every margin's loss on every set, and the leave-one-set-out choice."""
    table = {c: [_loss(r, c) for r in rows] for c in MARGINS}
    left_out = []
    for i, row in enumerate(rows):
        others = {c: sum(v for j, v in enumerate(table[c]) if j != i) for c in MARGINS}
        least = min(others.values())
        chosen = max(c for c in MARGINS if others[c] <= least + 1e-12)
        left_out.append({"name": row["name"], "margin": chosen, "loss": table[chosen][i]})
    n = max(len(rows), 1)
    return {
        "sets": rows,
        "margins": list(MARGINS),
        "losses": {str(c): v for c, v in table.items()},
        # geometric mean of the test-error ratio to the better pick, over the sets
        "ratio": {str(c): float(np.exp(sum(v) / n)) for c, v in table.items()},
        "left_out": left_out,
        "left_out_ratio": float(np.exp(sum(r["loss"] for r in left_out) / n)),
    }


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("results", type=Path)
    p.add_argument("--out", type=Path, help="write the study as JSON here")
    p.add_argument("--refine", type=int, help="score both candidates on this many folds too")
    p.add_argument("--nfev", type=int, help="with --refine: at least this many iterations")
    args = p.parse_args()
    out = study(decisions(args.results, args.refine, args.nfev))
    print(json.dumps({k: out[k] for k in ("ratio", "left_out", "left_out_ratio")}, indent=1))
    if args.out is not None:
        args.out.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
