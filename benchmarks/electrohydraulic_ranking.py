"""Paper B's model ranking on the simulated excavator arm, with blockid's own estimators.

Usage::

    python benchmarks/electrohydraulic_ranking.py [--seeds N] [--first-seed S] [--nk K]
        [--validation-bandwidth HZ|none] [--json] [--set NAME=VALUE ...]

For every seed ``s`` in ``S..S+N-1``: :func:`electrohydraulic_experiment` gives the averaged
multisine record (estimation) and one general-trajectory run (validation); the four
structures of paper B are identified with :func:`blockid.fitting.fit_model` at its
default method (free-run simulation error for the block-oriented models, batch least
squares for ARX) with paper B's orders (``na = 3``, ``nb = 3``, ``nk = 8``, ``r1 = r2 = 3``),
and each model is scored by the MSE of its free-run simulation on the validation record
(:func:`blockid.evaluation.evaluate`, mode ``"simulation"``). ``--validation-bandwidth``
sets the experiment's ``validation_bandwidth`` (default 0.5 Hz, the multisine's top
component; ``none`` for the step-like validation moves). ``--set`` overrides fields
of :class:`ElectrohydraulicParameters` (e.g. ``--set spool_damping=4650``) for
sensitivity studies.

Printed: the four MSEs per seed, the ratios H-W / Hammerstein, Hammerstein / Wiener and
Hammerstein / ARX, and how many seeds satisfy paper B's ordering (the issue's criterion):
H-W lowest, at least 10 % below Hammerstein, and both two-segment-input models (H-W,
Hammerstein) at most half the error of Wiener and of ARX ("far better"; paper B's
Table 2 has 0.30-0.39).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.plants.electrohydraulic import ElectrohydraulicParameters, electrohydraulic_experiment

STRUCTURES = ("hammerstein-wiener", "hammerstein", "wiener", "arx")
SHORT = {"hammerstein-wiener": "H-W", "hammerstein": "Ham", "wiener": "Wie", "arx": "ARX"}
#: Paper B, Table 2: prediction MSE of the four identified models.
PAPER = {"hammerstein-wiener": 0.0321, "hammerstein": 0.0417, "wiener": 0.1081, "arx": 0.1218}


def options(structure: str, nk: int) -> dict[str, int]:
    """Paper B's orders in blockid's convention (SPEC.md, Conventions)."""
    orders = {"na": 3, "nb": 3, "nk": nk}
    extra = {
        "arx": {},
        "hammerstein": {"r1": 3},
        "wiener": {"r2": 3},
        "hammerstein-wiener": {"r1": 3, "r2": 3},
    }[structure]
    return orders | extra


def run_seed(
    seed: int, nk: int, params: ElectrohydraulicParameters, bandwidth: float | None = 0.5
) -> dict[str, float]:
    """Validation free-run MSE of the four structures for one seed."""
    exp = electrohydraulic_experiment(seed=seed, params=params, validation_bandwidth=bandwidth)
    est = Dataset.from_frame(exp["estimation"], ["current"], ["velocity"], time_column="t")
    val = Dataset.from_frame(exp["validation"], ["current"], ["velocity"], time_column="t")
    out = {}
    for structure in STRUCTURES:
        fit = fit_model(est, structure, **options(structure, nk))
        out[structure] = evaluate(fit.model, val, "simulation").metrics["mse"]["velocity"]
    return out


def criteria(m: dict[str, float]) -> dict[str, bool]:
    """The three parts of paper B's ordering for one seed."""
    hw, ham, wie, arx = (m[s] for s in STRUCTURES)
    return {
        "lowest": hw < min(ham, wie, arx),
        "10% below Ham": hw <= 0.9 * ham,
        "far better": max(hw, ham) <= 0.5 * min(wie, arx),
    }


def parse_overrides(items: list[str]) -> ElectrohydraulicParameters:
    """``NAME=VALUE`` strings to a parameter set."""
    names = {f.name for f in dataclasses.fields(ElectrohydraulicParameters)}
    changes = {}
    for item in items:
        name, _, value = item.partition("=")
        if name not in names or not value:
            raise SystemExit(
                f"--set {item!r}: expected NAME=VALUE with NAME one of {sorted(names)}"
            )
        changes[name] = float(value)
    return dataclasses.replace(ElectrohydraulicParameters(), **changes)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default 10)")
    parser.add_argument("--first-seed", type=int, default=0, help="first seed (default 0)")
    parser.add_argument("--nk", type=int, default=8, help="input delay in samples (paper B: 8)")
    parser.add_argument(
        "--validation-bandwidth",
        default="0.5",
        help="corner of the validation command's low-pass [Hz], or 'none' (default 0.5)",
    )
    parser.add_argument(
        "--set", action="append", default=[], metavar="NAME=VALUE", help="plant parameter"
    )
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args()
    params = parse_overrides(args.set)
    value = args.validation_bandwidth.strip().lower()
    try:
        bandwidth = None if value == "none" else float(value)
    except ValueError:
        parser.error(f"--validation-bandwidth: expected Hz or 'none', got {value!r}")

    rows = []
    start = time.perf_counter()
    if not args.json:
        print("seed      H-W      Ham      Wie      ARX   H-W/Ham  Ham/Wie  Ham/ARX  ordering")
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        t0 = time.perf_counter()
        m = run_seed(seed, args.nk, params, bandwidth)
        c = criteria(m)
        rows.append(
            {
                "seed": seed,
                "mse": m,
                "criteria": c,
                "ok": all(c.values()),
                "seconds": time.perf_counter() - t0,
            }
        )
        if not args.json:
            hw, ham, wie, arx = (m[s] for s in STRUCTURES)
            failed = ", ".join(k for k, v in c.items() if not v)
            print(
                f"{seed:4d}  {hw:.5f}  {ham:.5f}  {wie:.5f}  {arx:.5f}   {hw / ham:6.3f}  "
                f"{ham / wie:7.3f}  {ham / arx:7.3f}  {'ok' if not failed else 'fails: ' + failed}",
                flush=True,
            )
    total = time.perf_counter() - start
    med = {s: float(np.median([r["mse"][s] for r in rows])) for s in STRUCTURES}

    def median_ratio(a: str, b: str) -> float:
        return float(np.median([r["mse"][a] / r["mse"][b] for r in rows]))

    ratios = {
        "H-W/Ham": median_ratio("hammerstein-wiener", "hammerstein"),
        "H-W/Wie": median_ratio("hammerstein-wiener", "wiener"),
        "H-W/ARX": median_ratio("hammerstein-wiener", "arx"),
        "Ham/Wie": median_ratio("hammerstein", "wiener"),
        "Ham/ARX": median_ratio("hammerstein", "arx"),
    }
    paper = {
        "H-W/Ham": PAPER["hammerstein-wiener"] / PAPER["hammerstein"],
        "H-W/Wie": PAPER["hammerstein-wiener"] / PAPER["wiener"],
        "H-W/ARX": PAPER["hammerstein-wiener"] / PAPER["arx"],
        "Ham/Wie": PAPER["hammerstein"] / PAPER["wiener"],
        "Ham/ARX": PAPER["hammerstein"] / PAPER["arx"],
    }
    counts = {k: sum(r["criteria"][k] for r in rows) for k in rows[0]["criteria"]}
    n_ok = sum(r["ok"] for r in rows)
    if args.json:
        print(
            json.dumps(
                {
                    "nk": args.nk,
                    "overrides": args.set,
                    "rows": rows,
                    "median_mse": med,
                    "median_ratio": ratios,
                    "paper_ratio": paper,
                    "criteria_counts": counts,
                    "satisfied": n_ok,
                    "seconds": total,
                },
                indent=2,
            )
        )
        return
    print(" med  " + "  ".join(f"{med[s]:.5f}" for s in STRUCTURES))
    print("median ratios: " + "  ".join(f"{k} {v:.3f}" for k, v in ratios.items()))
    print("paper B:       " + "  ".join(f"{k} {v:.3f}" for k, v in paper.items()))
    print(
        f"ordering satisfied on {n_ok} of {len(rows)} seeds ("
        + ", ".join(f"{k}: {v}" for k, v in counts.items())
        + f"); {total:.0f} s"
    )


if __name__ == "__main__":
    main()
