"""Welch's estimate of the frequency response against a known plant, and its bounds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from blockid.data import Dataset, Experiment
from blockid.errors import DataError, ParameterError
from blockid.evaluation import best_linear_approximation, welch_bla

#: A Butterworth low-pass behind a delay of two samples (the delay shows a sign error
#: of the cross-spectrum as a wrong phase).
B, A = np.concatenate([[0.0, 0.0], signal.butter(2, 0.3)[0]]), signal.butter(2, 0.3)[1]
TS = 0.01


def _noise_record(seed, n=8192, sigma=0.2, experiments=1):
    rng = np.random.default_rng(seed)
    exps = []
    for e in range(experiments):
        u = rng.standard_normal(n)
        exps.append(
            Experiment(f"e{e}", u, signal.lfilter(B, A, u) + sigma * rng.standard_normal(n))
        )
    return Dataset(("u",), ("y",), TS, exps)


def _truth(f):
    return signal.freqz(B, A, worN=2 * np.pi * f * TS)[1]


def test_the_estimate_matches_the_plant_within_its_bounds_over_many_records():
    """20 records: the 99 % bounds hold the true response at 99 % of the lines, and
    |e|² / σ² behaves as an exponential variable (P(|e|² < 3 σ²) = 95 %)."""
    held, held_3 = [], []
    for seed in range(20):
        bla = welch_bla(_noise_record(seed))
        error = np.abs(bla.g - _truth(bla.frequencies))
        held.append(np.mean(error <= bla.bound))
        held_3.append(np.mean(error**2 <= 3 * bla.var_total))
    assert np.mean(held) == pytest.approx(0.99, abs=0.01)
    assert np.mean(held_3) == pytest.approx(0.95, abs=0.02)


def test_the_coherence_is_the_share_of_the_output_the_input_explains():
    bla = welch_bla(_noise_record(1, n=32768))
    h = np.abs(_truth(bla.frequencies)) ** 2
    true = h / (h + 0.2**2)  # white input of unit power, white noise 0.04
    # less the estimate's bias (1 - γ²)² / n_d (Carter, Knapp & Nuttall 1973)
    expected = true + (1 - true) ** 2 / bla.segments
    assert abs(np.mean(bla.coherence - expected)) < 0.005
    strong = true > 0.9
    assert np.mean(np.abs(bla.coherence - expected)[strong]) < 0.02
    assert bla.var_noise is None and bla.nonexcited is None
    assert "noise and nonlinear distortion are not told apart" in bla.verdict


def test_experiments_are_pooled_and_the_segment_sets_the_resolution():
    bla = welch_bla(_noise_record(2, n=4096, experiments=3), segment=256)
    assert bla.samples == 256 and bla.frequencies[1] - bla.frequencies[0] == pytest.approx(
        1 / (256 * TS)
    )
    # 31 half-overlapping segments a record, over Welch's factor 1 + 2 (1/36) (30/31)
    assert bla.segments == pytest.approx(93 / (1 + 2 / 36 * 92 / 93))
    assert bla.realisations == 3


def test_non_periodic_data_get_the_welch_estimate_with_a_note():
    bla = best_linear_approximation(_noise_record(3))
    assert bla.method == "welch" and "the input does not repeat" in bla.notes[0]
    assert best_linear_approximation(_noise_record(3), segment=128).samples == 128


def test_bad_records_are_refused():
    data = _noise_record(4, n=256)
    with pytest.raises(ParameterError, match="segment = 512 samples is longer than the shortest"):
        welch_bla(data, segment=512)
    with pytest.raises(DataError, match="3 segment.s. of 128 samples make 2.9 independent"):
        welch_bla(data, segment=128)
    u = np.zeros(256)
    flat = Dataset(("u",), ("y",), TS, [Experiment("flat", u, u)])
    with pytest.raises(DataError, match="no power at any frequency"):
        welch_bla(flat)
    y = data.experiments[0].y[:, 0].copy()
    y[5] = np.inf
    bad = Dataset(("u",), ("y",), TS, [Experiment("x", data.experiments[0].u, y)])
    with pytest.raises(DataError, match="the output is inf at sample 5"):
        welch_bla(bad)
