"""The polynomial state space's state dimension: the default's choice against every order.

Usage: ``python benchmarks/real/pnlss_orders.py [--only NAME ...] [--orders 1 2 ...]
[--write-docs]``

For each set (the Silverbox, WH 2009 and the Bouc-Wen), ``fit_model(estimation,
"polynomial-state-space", degree=3)`` with every other option at its default: first
without ``nx`` (the order chosen on held-back halves of the estimation data, the
default), then with ``nx = 1 .. 6``; each fit's free-run RMSE on the set's test records
(started from its allowed initial outputs, as ``run.py`` scores), its fit time (one
process, every core) and how the refinement stopped. The doc's table says whether the
default's test error is within 15 % of the best order's (issue 36). Nothing here chooses
anything: the test records only score.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(1, str(Path(__file__).resolve().parent.parent))  # _report

from datasets import ALL, REPO, MissingData  # noqa: E402
from run import test_rmse  # noqa: E402

RESULTS = REPO / "benchmarks" / "results" / "pnlss_orders"
DOC = REPO / "docs" / "orders.md"
SETS = ("silverbox", "wh2009", "bouc_wen")
ORDERS = (1, 2, 3, 4, 5, 6)


def fit_one(bench: Any, nx: int | None) -> dict[str, Any]:
    from blockid.fitting.dispatch import fit_model

    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    fit = fit_model(bench.estimation, "polynomial-state-space", nx=nx, degree=3)
    seconds = time.perf_counter() - t0
    tests = {rec.name: test_rmse(fit.model, rec, bench.n_init)[0][0] * bench.scale
             for rec in bench.tests}  # fmt: skip
    st = fit.settings
    from blockid.fitting.state_space import subspace

    gap = subspace(bench.estimation, nx=None).nx  # the canonical-correlation gap's order
    return {
        "gap_nx": gap,
        "nx": st["nx"], "given": nx is not None, "seconds": seconds, "load": load,
        "tests": tests, "iterations": st.get("iterations"),
        "evaluations": st.get("function_evaluations"), "stop_reason": st.get("stop_reason"),
        "order_scores": st.get("order_scores"), "parameters": int(fit.model.n_free_parameters),
    }  # fmt: skip


def screen_scores(
    bench: Any, orders: list[int], degree: int = 2, nfev: int = 30
) -> dict[int, float]:
    """The free-run error (RMSE over the output's spread) on each held-back half of the
    estimation data of a model of the given degree and each order
    (``order_by_validation``'s two folds and scoring, at most ``nfev`` simulations per
    fit): the rules tried and not taken in ``docs/orders.md``. An order whose start or
    fit fails on a half scores infinity."""
    import numpy as np

    from blockid.data.folds import fold_plan, materialise
    from blockid.fitting.state_space import fit_polynomial_state_space

    data = bench.estimation
    plan = fold_plan(data, 2, min_samples=60)
    spread = np.maximum(np.vstack([e.y for e in data.experiments]).std(axis=0), 1e-300)
    label = getattr(bench, "name", "")
    scores = {}
    for n in orders:
        squares, count = 0.0, 0
        for fold in plan.folds:
            train, test = materialise(data, fold.train), materialise(data, fold.test)
            try:
                model = fit_polynomial_state_space(train, nx=n, degree=degree, max_nfev=nfev)
            except Exception as exc:  # noqa: BLE001 - a failed order scores infinity
                print(label, n, "failed:", exc)
                squares = math.inf
                break
            for e in test.experiments:
                start = min(50, e.n_samples // 4)
                with np.errstate(all="ignore"):
                    sim = model.model.simulate(e.u, e.y[:start])
                err = ((e.y[start:] - sim[start:]) / spread).ravel()
                squares, count = squares + float(err @ err), count + err.size
        scores[n] = float(np.sqrt(squares / max(count, 1))) if np.isfinite(squares) else math.inf
        print(label, n, round(scores[n], 5), flush=True)
    return scores


def _table(name: str, runs: list[dict[str, Any]], unit: str, title: str) -> list[str]:
    default = next(r for r in runs if not r["given"])
    given = [r for r in runs if r["given"]]
    records = list(default["tests"])
    lines = [f"### {title}", ""]
    scores = default.get("order_scores") or []
    if scores:
        shown = ", ".join(
            f"nx {s['nx']}: {s['error']:.4g}" if s.get("error") is not None else f"nx {s['nx']}: -"
            for s in scores
        )
        lines += [
            "The default's scores (free-run RMSE over the output's spread on the held-back "
            f"half, linear models): {shown}; chosen **nx = {default['nx']}**. The "
            "canonical correlations' largest gap (the default before) reads nx = "
            f"{default.get('gap_nx', '?')}.",
            "",
        ]
    head = " | ".join(f"{r} ({unit})" for r in records)
    lines += [
        f"| nx | {head} | parameters | iterations (evaluations) | stop | fit s | load |",
        "|---|" + "---:|" * len(records) + "---:|---|---|---:|---:|",
    ]
    for r in [default, *given]:
        label = f"default (nx = {r['nx']})" if not r["given"] else str(r["nx"])
        cells = " | ".join(f"{r['tests'][k]:.4g}" for k in records)
        lines.append(f"| {label} | {cells} | {r['parameters']} | {r['iterations']} "
                     f"({r['evaluations']}) | {r['stop_reason']} | {r['seconds']:.0f} | "
                     f"{r['load']:.1f} |")  # fmt: skip
    first = records[0]
    best = min(given, key=lambda r: r["tests"][first]) if given else None
    if best is not None:
        ratio = default["tests"][first] / best["tests"][first]
        lines += ["", f"On `{first}` the default tests {ratio:.2f} times the best order's "
                      f"(nx = {best['nx']}): {'within' if ratio <= 1.15 else '**not** within'} "
                      "15 %."]  # fmt: skip
    return [*lines, ""]


def write_doc(results: dict[str, list[dict[str, Any]]], titles: dict[str, tuple[str, str]]) -> None:
    from _report import machine, write_section

    lines = [
        "## The polynomial state space's default state dimension (issue 36)",
        "",
        "`python benchmarks/real/pnlss_orders.py` — `fit_model(estimation, "
        '"polynomial-state-space", degree=3)` with every other option at its default, '
        "first without `nx` (the default: the smallest order whose linear model simulates "
        "the held-back half of the estimation data within 2 % of the best, "
        "`blockid.fitting.state_space.order_by_validation`), then with each `nx`. Free-run "
        "simulation RMSE on each set's test records, started from the allowed initial "
        "outputs (as `benchmarks/real/run.py`); the test records only score, they choose "
        f"nothing. One process on every core. Machine: {machine()}.",
        "",
    ]
    for name, runs in results.items():
        unit, title = titles[name]
        lines += _table(name, runs, unit, title)
    write_section("pnlss-orders", "\n".join(lines), DOC)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--only", nargs="+", choices=SETS, default=list(SETS))
    p.add_argument("--orders", nargs="*", type=int, default=list(ORDERS),
                   help="the given orders to fit (none: the default's fit alone)")  # fmt: skip
    p.add_argument("--degree2", action="store_true",
                   help="only the degree-2 models' held-back scores of each order (a rule "
                        "tried and not taken: docs/orders.md)")  # fmt: skip
    p.add_argument("--degree3", action="store_true",
                   help="only the degree-3 models' held-back scores of each order (the "
                        "fit's own degree; tried and not taken: docs/orders.md)")  # fmt: skip
    p.add_argument("--write-docs", action="store_true")
    p.add_argument("--docs-only", action="store_true")
    args = p.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    titles = {}
    for name in args.only:
        try:
            bench = ALL[name]()
        except MissingData as exc:
            print(f"{name}: {exc}")
            continue
        titles[name] = (bench.unit, bench.title)
        if args.docs_only:
            continue
        if args.degree2 or args.degree3:
            degree = 3 if args.degree3 else 2
            scores = screen_scores(bench, args.orders, degree)
            (RESULTS / f"{name}_degree{degree}.json").write_text(json.dumps(scores, indent=1))
            continue
        for nx in [None, *args.orders]:
            f = RESULTS / f"{name}_{'default' if nx is None else nx}.json"
            run = fit_one(bench, nx)
            f.write_text(json.dumps(run, indent=1, default=str))
            print(name, nx, run["nx"], {k: round(v, 4) for k, v in run["tests"].items()},
                  f"{run['seconds']:.0f} s", run["stop_reason"], flush=True)  # fmt: skip
    if args.write_docs or args.docs_only:
        results = {}
        for name in SETS:  # every set with results, whatever --only ran this time
            if name not in titles:
                try:
                    bench = ALL[name]()
                except MissingData:
                    continue
                titles[name] = (bench.unit, bench.title)
            runs = [json.loads((RESULTS / f"{name}_{k}.json").read_text())
                    for k in ["default", *map(str, ORDERS)]
                    if (RESULTS / f"{name}_{k}.json").exists()]  # fmt: skip
            if runs and any(not r["given"] for r in runs):
                results[name] = runs
        write_doc(results, titles)
        print(f"wrote {DOC}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
