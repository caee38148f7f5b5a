"""Where in frequency the validation error of paper B's models lies.

Usage::

    python benchmarks/electrohydraulic_bands.py [--seeds N] [--validation-bandwidth HZ|none]
        [--split HZ] [--json]

For every seed ``0..N-1``: the experiment of :func:`electrohydraulic_experiment` (with the
given ``validation_bandwidth``; default ``none``, the step-like validation moves), the
Hammerstein-Wiener and Hammerstein models fitted with blockid's default estimator and
paper B's orders, and their free-run simulation errors on the validation record. Each
error is split by its periodogram into the power at or below ``--split`` (default
0.55 Hz, just above the multisine's top component 0.5 Hz: the band the estimation
record excites) and above it. Also printed: the share of the validation *input's* power
above the split, and the share of the estimation input's.

The measurement noise of the differentiated angle (about 1.5e-4 (rad/s)^2 in one
validation run) is white in the angle, so its velocity is blue and lies mostly above
the split: the split shows which model is better where the data could tell, and how
much of the MSE is decided where they could not.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from blockid.data import Dataset
from blockid.evaluation import evaluate
from blockid.fitting import fit_model
from blockid.plants.electrohydraulic import electrohydraulic_experiment

ORDERS = {
    "hammerstein-wiener": {"na": 3, "nb": 3, "nk": 8, "r1": 3, "r2": 3},
    "hammerstein": {"na": 3, "nb": 3, "nk": 8, "r1": 3},
}


def band_power(signal: np.ndarray, split: float, sample_time: float) -> tuple[float, float]:
    """Mean-square power of ``signal`` (mean removed) at or below and above ``split`` Hz."""
    centred = signal - signal.mean()
    power = np.abs(np.fft.rfft(centred)) ** 2 / centred.size**2
    power[1:] *= 2.0  # one-sided
    if centred.size % 2 == 0:
        power[-1] /= 2.0  # the Nyquist bin appears once
    freqs = np.fft.rfftfreq(centred.size, sample_time)
    return float(power[freqs <= split].sum()), float(power[freqs > split].sum())


def run_seed(seed: int, bandwidth: float | None, split: float) -> dict:
    exp = electrohydraulic_experiment(seed=seed, validation_bandwidth=bandwidth)
    est = Dataset.from_frame(exp["estimation"], ["current"], ["velocity"], time_column="t")
    val = Dataset.from_frame(exp["validation"], ["current"], ["velocity"], time_column="t")
    ts = float(val.sampling_time)
    y = val.experiments[0].y[:, 0]
    row: dict = {"seed": seed}
    for name, data in (("validation input", val), ("estimation input", est)):
        low, high = band_power(data.experiments[0].u[:, 0], split, ts)
        row[name] = high / (low + high)
    for structure, orders in ORDERS.items():
        model = fit_model(est, structure, **orders).model
        error = evaluate(model, val, "simulation").outputs[0][:, 0] - y
        low, high = band_power(error, split, ts)
        row[structure] = {"low": low, "high": high, "mse": float(np.mean(error**2))}
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..N-1 (default 10)")
    parser.add_argument(
        "--validation-bandwidth", default="none", help="Hz or 'none' (default none)"
    )
    parser.add_argument("--split", type=float, default=0.55, help="band split [Hz]")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args()
    value = args.validation_bandwidth.strip().lower()
    try:
        bandwidth = None if value == "none" else float(value)
    except ValueError:
        parser.error(f"--validation-bandwidth: expected Hz or 'none', got {value!r}")
    rows = [run_seed(seed, bandwidth, args.split) for seed in range(args.seeds)]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    s = args.split
    print(
        f"seed  val-in >{s}Hz  est-in >{s}Hz  H-W <={s}  Ham <={s}  ratio   "
        f"H-W >{s}  Ham >{s}  ratio   MSE ratio"
    )
    for r in rows:
        hw, ham = r["hammerstein-wiener"], r["hammerstein"]
        print(
            f"{r['seed']:4d}  {r['validation input']:12.3f}  {r['estimation input']:12.4f}  "
            f"{hw['low']:.2e}  {ham['low']:.2e}  {hw['low'] / ham['low']:5.2f}   "
            f"{hw['high']:.2e}  {ham['high']:.2e}  {hw['high'] / ham['high']:5.2f}   "
            f"{hw['mse'] / ham['mse']:9.2f}"
        )
    wins_low = sum(r["hammerstein-wiener"]["low"] < 0.9 * r["hammerstein"]["low"] for r in rows)
    wins_all = sum(r["hammerstein-wiener"]["mse"] < 0.9 * r["hammerstein"]["mse"] for r in rows)
    print(
        f"H-W at least 10 % below Hammerstein: at or below {s} Hz on {wins_low} of {len(rows)} "
        f"seeds; in the whole MSE on {wins_all} of {len(rows)}"
    )


if __name__ == "__main__":
    main()
