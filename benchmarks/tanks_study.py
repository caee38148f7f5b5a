"""A short, slow record kept apart from the shared sets: what ``identify`` chooses.

Usage: ``python benchmarks/tanks_study.py [--seeds 1 2 3] [--efforts standard thorough]
[--experiments] [--write-docs]``

Issue 35 reports a real record of 1 024 estimation samples (4 folds of 256) where the
standard effort returned a model no better than the linear one while the thorough
effort found a polynomial state space that tested 49 % better. That record is not in
``../shared/data``; this study simulates one like it, so that the effect can be measured
here: two tanks in cascade, each draining through an orifice (outflow proportional to
the square root of the level), the upper one overflowing at 10 into the lower one, the
lower level measured (its sensor clips at 10). The input is a random-phase multisine
(60 lines, 1 024 samples a period, sampling time 4 s, clipped to 0-10), the estimation
and test records two realisations of it, with process noise on the levels and white
noise on the measurement.

For each seed: ``identify`` at each effort on the estimation record (chosen model, its
cross-validated score, search time), and direct fits for reference (a linear state
space and polynomial state spaces of 2 and 3 states); every model's free-run RMSE on the
test record from its 20 first measured outputs (the test record chooses nothing).

``--experiments``: instead, ``identify`` (standard) on three realisations of the seed's
plant as three experiments (the seed's two records and the first of seed + 10; the
search then holds one experiment out per fold), tested on the second record of seed +
10, beside the same direct fits on the three.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

DOC = Path(__file__).resolve().parent.parent / "docs" / "identify.md"
N = 1024  # samples in each record
TS = 4.0
N_INIT = 20  # measured test outputs a model may start from
#: outflow coefficients of the upper and lower tank, the lower tank's inflow from the
#: upper one, the pump's gain, and the share of the upper tank's overflow that reaches
#: the lower one
K1, K2, K3, K4, K5 = 0.035, 0.035, 0.03, 0.021, 0.5
REFERENCES: tuple[tuple[str, dict[str, Any]], ...] = (
    ("state-space", {"nx": 2}),
    ("polynomial-state-space", {"nx": 2, "degree": 3, "monomials": "states"}),
    ("polynomial-state-space", {"nx": 3, "degree": 2}),
)


def _multisine(rng: np.random.Generator, lines: int = 60) -> np.ndarray:
    spectrum = np.zeros(N // 2 + 1, complex)
    spectrum[1 : lines + 1] = np.exp(2j * np.pi * rng.random(lines))
    u = np.fft.irfft(spectrum, N)
    return np.clip(4.0 + 2.6 * u / u.std(), 0.0, 10.0)


def _levels(u: np.ndarray, rng: np.random.Generator, steps: int = 40, tank: int = 1) -> np.ndarray:
    """A tank's level at each sample (``tank`` 1: the lower, measured one; 0: the upper);
    RK4, ``steps`` per sample, the input held."""

    def rate(x: np.ndarray, uk: float) -> np.ndarray:
        s1, s2 = np.sqrt(max(x[0], 0.0)), np.sqrt(max(x[1], 0.0))
        return np.array([-K1 * s1 + K4 * uk, K2 * s1 - K3 * s2])

    h, x, out = TS / steps, np.array([4.0, 4.0]), np.empty(len(u))
    for k, uk in enumerate(u):
        out[k] = x[tank]
        for _ in range(steps):
            a = rate(x, uk)
            b = rate(x + h / 2 * a, uk)
            c = rate(x + h / 2 * b, uk)
            d = rate(x + h * c, uk)
            x = x + h / 6 * (a + 2 * b + 2 * c + d)
            if x[0] > 10.0:  # the upper tank overflows, partly into the lower one
                x[1] += K5 * (x[0] - 10.0)
                x[0] = 10.0
            x[1] = min(x[1], 10.0)
        x = x + 0.01 * rng.standard_normal(2)
    return out


def records(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Estimation and test input and output of one seed."""
    rng = np.random.default_rng(seed)
    ue, ut = _multisine(rng), _multisine(rng)
    ye, yt = _levels(ue, rng), _levels(ut, rng)
    ye = ye + 0.03 * rng.standard_normal(N)
    yt = yt + 0.03 * rng.standard_normal(N)
    return ue, ye, ut, yt


def upper_levels(u: np.ndarray, seed: int = 0) -> np.ndarray:
    """The upper tank's level driven by ``u`` (process noise of ``seed``): where it
    sits at 10, it overflows."""
    return _levels(u, np.random.default_rng(seed), tank=0)


def test_error(model: Any, u: np.ndarray, y: np.ndarray) -> float:
    with np.errstate(all="ignore"):
        sim = np.asarray(model.simulate(u[:, None], y[:N_INIT, None])).reshape(-1)
    err = y[N_INIT:] - sim[N_INIT:]
    return float(np.sqrt(np.mean(err**2))) if np.all(np.isfinite(err)) else float("inf")


def _label(structure: str, options: dict[str, Any]) -> str:
    return f"{structure}({', '.join(f'{k}={v}' for k, v in options.items())})"


def _identified(seed: int, what: str, data: Any, ut: np.ndarray, yt: np.ndarray,
                **kwargs: Any) -> dict[str, Any]:  # fmt: skip
    """``identify`` on ``data`` (its keywords ``kwargs``) and the chosen model's test error."""
    from blockid.workflows.identify import identify

    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    result = identify(data, **kwargs)
    row = {
        "seed": seed, "what": what, "model": result.selected.candidate.label,
        "cv": result.selected.rmse, "test": test_error(result.model, ut, yt),
        "seconds": time.perf_counter() - t0, "load": load,
    }  # fmt: skip
    print(row, flush=True)
    return row


Reference = tuple[tuple[str, dict[str, Any]], ...]


def _direct(seed: int, what: str, data: Any, ut: np.ndarray, yt: np.ndarray,
            references: Reference) -> list[dict[str, Any]]:  # fmt: skip
    """Each reference structure fitted directly on ``data`` and its test error (inf when
    the fit fails: a study reports it)."""
    from blockid.fitting.dispatch import fit_model

    rows = []
    for structure, options in references:
        t0 = time.perf_counter()
        try:
            with np.errstate(all="ignore"):
                err = test_error(fit_model(data, structure, **options).model, ut, yt)
        except Exception as exc:  # noqa: BLE001 - a study: a failed fit is reported
            err = float("inf")
            print(f"seed {seed}: {_label(structure, options)} failed: {exc}", flush=True)
        rows.append({
            "seed": seed, "what": what, "model": _label(structure, options), "cv": None,
            "test": err, "seconds": time.perf_counter() - t0, "load": None,
        })  # fmt: skip
        print(rows[-1], flush=True)
    return rows


def study(seed: int, efforts: list[str]) -> list[dict[str, Any]]:
    """``identify`` at each effort on the seed's estimation record, and the direct fits."""
    from blockid.data.dataset import Dataset

    ue, ye, ut, yt = records(seed)
    data = Dataset.from_arrays(ue[:, None], ye[:, None], sampling_time=TS)
    rows = [_identified(seed, f"identify, {e}", data, ut, yt, effort=e) for e in efforts]
    return rows + _direct(seed, "direct fit", data, ut, yt, REFERENCES)


def study_experiments(seed: int) -> list[dict[str, Any]]:
    """``identify`` on three realisations as three experiments (module docstring)."""
    from blockid.data.dataset import Dataset, Experiment

    first, second = records(seed), records(seed + 10)
    pairs = [(first[0], first[1]), (first[2], first[3]), (second[0], second[1])]
    exps = [
        Experiment(f"realisation {i + 1}", u[:, None], y[:, None]) for i, (u, y) in enumerate(pairs)
    ]
    data = Dataset(("u",), ("y",), TS, exps)
    ut, yt = second[2], second[3]
    row = _identified(seed, "identify, standard, 3 experiments", data, ut, yt)
    return [row, *_direct(seed, "direct fit, 3 experiments", data, ut, yt, REFERENCES[:2])]


def table(rows: list[dict[str, Any]]) -> list[str]:
    lines = [
        "| seed | how | model | CV RMSE | test RMSE | s | load |",
        "|---:|---|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        cv = "-" if r["cv"] is None else f"{r['cv']:.3f}"
        load = "-" if r["load"] is None else f"{r['load']:.1f}"
        lines.append(
            f"| {r['seed']} | {r['what']} | `{r['model']}` | {cv} | {r['test']:.3f} | "
            f"{r['seconds']:.0f} | {load} |"
        )
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--efforts", nargs="+", default=["standard", "thorough"])
    ap.add_argument("--experiments", action="store_true")
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    if args.experiments:
        rows = [r for seed in args.seeds for r in study_experiments(seed)]
        section, intro = (
            "tanks-experiments",
            (
                "`python benchmarks/tanks_study.py --experiments` (machine: {machine}): three "
                "realisations of each seed's plant as three experiments of 1 024 samples (the "
                "search holds one out per fold), a fourth to test on. Free-run simulation RMSE "
                "on it from its first {n} measured outputs."
            ),
        )
    else:
        rows = [r for seed in args.seeds for r in study(seed, args.efforts)]
        section, intro = (
            "tanks-study",
            (
                "`python benchmarks/tanks_study.py` (machine: {machine}): the simulated cascaded "
                "tanks of the module docstring, one record of 1 024 samples per seed to estimate "
                "on and one to test on. Free-run simulation RMSE on the test record (level "
                "units, 0-10), each model started from its first {n} measured outputs; CV RMSE "
                "is the search's cross-validated score of the chosen model."
            ),
        )
    lines = [intro.format(machine=machine(), n=N_INIT), "", *table(rows)]
    print("\n".join(lines))
    if args.write_docs:
        write_section(section, "\n".join(lines), DOC)


if __name__ == "__main__":
    main()
