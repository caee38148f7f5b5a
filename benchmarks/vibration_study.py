"""A vibrating structure of one input and three outputs, like the F-16 ground vibration
test: what ``identify`` chooses, and what a cubic polynomial in the loop would add.

Usage: ``python benchmarks/vibration_study.py [--seeds 1 2 3] [--write-docs]``

The F-16 record is not in ``../shared/data``; this study simulates a structure like it,
so that what ``identify`` does on such a record can be measured here. Three lightly
damped modes (7.3, 12.9 and 19.5 Hz; damping 2, 1.5 and 3 %) driven by one force, the
second mode's coordinate meeting a hardening joint (a cubic stiffness), measured as
three accelerations (direct feedthrough from the force); 400 samples a second,
integrated by fourth-order Runge-Kutta (four steps a sample, the force held). The input
is a random-phase multisine of 8 192 samples a period up to 40 Hz; the estimation
record five periods after one dropped (40 960 samples), the test record one period of
another realisation after one dropped; white noise at 2 % of each output's spread. Seed
``s`` draws the estimation record from ``2 s - 1`` and the test record from ``2 s``.

Rows: ``identify`` at the standard effort; the same search with a cubic polynomial
among its loop blocks (an :class:`~blockid.workflows.effort.Effort` passed in, not the
default: ``docs/identify.md``, the cubic loop study); direct fits of a linear state
space and of a block state space with a cubic loop. Free-run simulation RMSE on the
test record of each output from its first 50 measured outputs; the test record chooses
nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import machine, write_section  # noqa: E402

DOC = Path(__file__).resolve().parent.parent / "docs" / "identify.md"
FS = 400.0  # samples a second
PERIOD = 8192
N_INIT = 50
HZ = np.array([7.3, 12.9, 19.5])
DAMPING = np.array([0.02, 0.015, 0.03])
SHAPES = np.array([[1.0, 0.6, 0.3], [0.8, -0.7, 0.5], [0.4, 0.9, -0.8]])  # sensor x mode
FORCE = np.array([1.0, 0.7, 0.5])  # the force's share in each mode
CUBIC = 3e4  # the joint's cubic stiffness on the second mode's coordinate
DIRECT: tuple[tuple[str, dict[str, Any]], ...] = (
    ("state-space", {"nx": 6}),
    ("state-space", {"nx": 8}),
    ("block-state-space", {"nx": 8, "loop_block": "polynomial:degree=3"}),
)


def _acceleration(q: np.ndarray, v: np.ndarray, force: float) -> np.ndarray:
    w = 2 * np.pi * HZ
    a = FORCE * force - 2 * DAMPING * w * v - w**2 * q
    a[1] -= CUBIC * q[1] ** 3
    return a


def accelerations(u: np.ndarray, steps: int = 4) -> np.ndarray:
    """The three sensors' accelerations under the force ``u`` (held over each sample)."""
    q, v, h = np.zeros(3), np.zeros(3), 1.0 / FS / steps
    y = np.empty((u.size, 3))
    for t, force in enumerate(u):
        y[t] = SHAPES @ _acceleration(q, v, force)
        for _ in range(steps):
            k1q, k1v = v, _acceleration(q, v, force)
            k2q, k2v = v + h / 2 * k1v, _acceleration(q + h / 2 * k1q, v + h / 2 * k1v, force)
            k3q, k3v = v + h / 2 * k2v, _acceleration(q + h / 2 * k2q, v + h / 2 * k2v, force)
            k4q, k4v = v + h * k3v, _acceleration(q + h * k3q, v + h * k3v, force)
            q = q + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
            v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return y


def record(periods: int, seed: int, rms: float = 60.0) -> tuple[np.ndarray, np.ndarray]:
    """``periods`` periods of a multisine realisation (the first dropped) and the noisy
    accelerations."""
    rng = np.random.default_rng(seed)
    lines = np.arange(1, int(40.0 / FS * PERIOD))
    spectrum = np.zeros(PERIOD // 2 + 1, complex)
    spectrum[lines] = np.exp(2j * np.pi * rng.random(lines.size))
    one = np.fft.irfft(spectrum, PERIOD)
    u = np.tile(one * rms / one.std(), periods)
    y = accelerations(u)[PERIOD:]
    return u[PERIOD:], y + 0.02 * y.std(axis=0) * rng.standard_normal(y.shape)


def test_errors(model: Any, u: np.ndarray, y: np.ndarray) -> list[float]:
    with np.errstate(all="ignore"):
        sim = np.asarray(model.simulate(u[:, None], y[:N_INIT]))
    err = y[N_INIT:] - sim[N_INIT:]
    return [float(v) for v in np.sqrt(np.mean(err**2, axis=0))]


def rows(seed: int) -> list[dict[str, Any]]:
    from blockid.data.dataset import Dataset
    from blockid.fitting.dispatch import fit_model
    from blockid.workflows.effort import EFFORTS
    from blockid.workflows.identify import identify

    ue, ye = record(6, seed=2 * seed - 1)
    ut, yt = record(2, seed=2 * seed)
    data = Dataset.from_arrays(ue, ye, outputs=["a1", "a2", "a3"], sampling_time=1 / FS)
    standard = EFFORTS["standard"]
    cubic = dataclasses.replace(standard, loop_plans=(*standard.loop_plans, "polynomial:degree=3"))
    out = []
    for what, effort in (("identify, standard", standard), ("identify, + cubic loop", cubic)):
        load, t0 = os.getloadavg()[0], time.perf_counter()
        result = identify(data, effort=effort)
        out.append({"seed": seed, "what": what, "model": result.selected.candidate.label,
                    "cv": result.selected.rmse, "test": test_errors(result.model, ut, yt),
                    "seconds": time.perf_counter() - t0, "load": load})  # fmt: skip
        print(out[-1], flush=True)
    for structure, options in DIRECT:
        load, t0 = os.getloadavg()[0], time.perf_counter()
        label = f"{structure}({', '.join(f'{k}={v}' for k, v in options.items())})"
        try:
            tests = test_errors(fit_model(data, structure, **options).model, ut, yt)
        except Exception as exc:  # noqa: BLE001 - a study: a failed fit is reported, not fatal
            print(f"seed {seed}: {label} failed: {exc}", flush=True)
            tests = [float("inf")] * yt.shape[1]
        out.append({"seed": seed, "what": "direct fit", "model": label, "cv": None,
                    "test": tests, "seconds": time.perf_counter() - t0,
                    "load": load})  # fmt: skip
        print(out[-1], flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--write-docs", action="store_true")
    args = ap.parse_args()
    lines = [
        f"`python benchmarks/vibration_study.py` (machine: {machine()}): the simulated "
        "structure of the module docstring, 40 960 samples to estimate on, 8 192 to test "
        "on, per seed. Free-run simulation RMSE of each acceleration on the test record, started "
        f"from its first {N_INIT} measured outputs (the outputs' spreads are about 215, "
        "188 and 194, the noise's 2 % of them); CV RMSE is the search's score of the "
        "chosen model, averaged over the outputs.",
        "",
        "| seed | how | model | CV RMSE | test RMSE (a1 / a2 / a3) | s | load |",
        "|---:|---|---|---:|---|---:|---:|",
    ]
    for r in [r for seed in args.seeds for r in rows(seed)]:
        cv = "-" if r["cv"] is None else f"{r['cv']:.2f}"
        tests = " / ".join(f"{v:.2f}" for v in r["test"])
        lines.append(f"| {r['seed']} | {r['what']} | `{r['model']}` | {cv} | {tests} | "
                     f"{r['seconds']:.0f} | {r['load']:.1f} |")  # fmt: skip
    print("\n".join(lines))
    if args.write_docs:
        write_section("vibration-study", "\n".join(lines), DOC)


if __name__ == "__main__":
    main()
