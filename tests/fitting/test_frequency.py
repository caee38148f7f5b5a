"""The transfer function fitted to a frequency response against a known plant: the true
coefficients within their estimated uncertainty, the uncertainty itself right over many
noise draws, and the same through a measured BLA."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal, stats

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.design import multisine
from blockid.errors import DataError, OrderError
from blockid.evaluation import best_linear_approximation
from blockid.fitting.frequency import fit_bla, fit_frequency_response

A_TRUE = np.array([-1.2, 0.5])  # poles 0.6 +- 0.37j
B_TRUE = np.array([0.5, 0.3])  # z^-1 (0.5 + 0.3 z^-1)
THETA = np.r_[A_TRUE, B_TRUE]


def _measured(seed, lines=200):
    """``G`` of the plant at ``lines`` lines, circular complex noise of known variance
    (larger at high frequency)."""
    rng = np.random.default_rng(seed)
    f = np.linspace(0.002, 0.498, lines)
    z1 = np.exp(-2j * np.pi * f)
    g = z1 * (B_TRUE[0] + B_TRUE[1] * z1) / (1 + A_TRUE[0] * z1 + A_TRUE[1] * z1**2)
    var = 1e-3 * (1 + 4 * f)
    noise = np.sqrt(var / 2) * (rng.standard_normal(lines) + 1j * rng.standard_normal(lines))
    return f, g + noise, var


def test_the_true_coefficients_lie_within_their_uncertainty():
    f, g, var = _measured(0)
    fit = fit_frequency_response(f, g, var, na=2, nb=2, nk=1)
    err = np.r_[fit.a, fit.b] - THETA
    assert np.all(np.abs(err) < 3.3 * fit.standard_errors)  # 99.9 % each
    distance = err @ np.linalg.solve(fit.covariance, err)
    assert distance < stats.chi2.ppf(0.999, 4)
    assert 0.8 < fit.cost_ratio < 1.2  # V about F - n/2: the model is right
    assert np.all(fit.standard_errors < 0.05)
    model = fit.model()
    assert model.structure == "output-error" and model.max_lag == 2
    assert fit.to_dict()["stable"] is True


def test_the_uncertainty_is_right_over_many_noise_draws():
    """95 % intervals of each coefficient hold it in 95 % of 200 draws (binomial spread
    of 200 draws: 0.92 to 0.98 at 3 sigma), and the spread of the estimates is the
    standard error predicted."""
    estimates, errors = [], []
    for seed in range(200):
        fit = fit_frequency_response(*_measured(seed, lines=60), na=2, nb=2, nk=1)
        estimates.append(np.r_[fit.a, fit.b])
        errors.append(fit.standard_errors)
    estimates, errors = np.array(estimates), np.array(errors)
    inside = np.mean(np.abs(estimates - THETA) < 1.96 * errors, axis=0)
    assert np.all((inside > 0.9) & (inside < 0.99)), inside
    ratio = estimates.std(axis=0) / errors.mean(axis=0)
    assert np.all((ratio > 0.85) & (ratio < 1.15)), ratio


def test_a_plant_measured_by_its_bla():
    """A second-order low-pass through the BLA of a multisine with output noise: the fit
    of the BLA holds the filter's coefficients within its uncertainty."""
    b, a = signal.butter(2, 0.2)  # b0 + b1 z^-1 + b2 z^-2, nk 0
    x = multisine(512, f_max=0.45, periods=3, realisations=6, seed=2)
    rng = np.random.default_rng(1)
    experiments = []
    for m, u in enumerate(x.signals):
        y = signal.lfilter(b, a, u) + 0.01 * rng.standard_normal(u.size)
        experiments.append(Experiment(f"r{m}", u, y))
    bla = best_linear_approximation(Dataset(("u",), ("y",), 1.0, experiments),
                                    transient_periods=1)  # fmt: skip
    fit = fit_bla(bla, na=2, nb=3, nk=0)
    err = np.r_[fit.a, fit.b] - np.r_[a[1:], b]
    assert np.all(np.abs(err) < 3.3 * fit.standard_errors), (err, fit.standard_errors)
    assert np.max(np.abs(err)) < 5e-3
    assert 0.7 < fit.cost_ratio < 1.4  # weighted by variances of 6 realisations: 1.25 corrected
    under = fit_bla(bla, na=1, nb=1, nk=0)  # too few poles: the cost says so
    assert under.cost_ratio > 10


def test_bad_orders_and_too_few_lines_are_named():
    f, g, var = _measured(0, lines=3)
    with pytest.raises(OrderError, match="nb must be a whole number >= 1"):
        fit_frequency_response(f, g, var, na=2, nb=0)
    with pytest.raises(DataError, match="too few for 4 \\+ 4 coefficients"):
        fit_frequency_response(f, g, var, na=4, nb=4)
