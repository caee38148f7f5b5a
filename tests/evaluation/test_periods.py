"""The period of a record found from its input, and records cut into periods."""

from __future__ import annotations

import numpy as np
import pytest

from blockid.data import Dataset, Experiment
from blockid.design import multisine, prbs
from blockid.errors import DataError, ParameterError
from blockid.evaluation.periods import find_period, periodic_frames


@pytest.mark.parametrize("samples", [64, 500, 1023, 4096])
def test_the_period_of_a_multisine_is_found(samples):
    x = multisine(samples, f_max=0.25, periods=3, seed=2)
    assert find_period(x.signals[0]) == samples


def test_the_period_of_a_measured_input_is_found_through_its_noise():
    x = multisine(1000, f_max=0.1, periods=4, seed=3)
    noisy = x.signals[0] + 0.2 * np.random.default_rng(1).standard_normal(4000)  # 14 dB
    assert find_period(noisy) == 1000


def test_a_slow_signal_is_not_taken_for_a_short_period():
    """Over-sampled 50 times, neighbouring samples correlate at 0.99: the period is the
    repeat after the fall, not the first lag."""
    x = multisine(2000, f_max=0.01, periods=3, seed=4)
    assert find_period(x.signals[0]) == 2000


def test_a_prbs_and_a_held_signal_repeat_with_their_period():
    assert find_period(prbs(7, periods=3).signals[0]) == 127
    assert find_period(prbs(6, clock=4, periods=2).signals[0]) == 252


def test_nothing_repeats_in_noise_or_in_one_period():
    rng = np.random.default_rng(0)
    assert find_period(rng.standard_normal(5000)) is None
    assert find_period(multisine(512, seed=1).signals[0]) is None  # one period
    assert find_period(np.ones(100)) is None and find_period([1.0, 2.0]) is None


def _data(n_periods=3, samples=64, realisations=2):
    x = multisine(samples, periods=n_periods, realisations=realisations, seed=0)
    exps = [Experiment(f"r{m}", u, 2 * u) for m, u in enumerate(x.signals)]
    return Dataset(("u",), ("y",), 1.0, exps)


def test_frames_are_the_periods_less_the_transient():
    data = _data()
    u, y, held = periodic_frames(data, transient_periods=1)
    assert u.shape == y.shape == (2, 2, 64) and held == 3
    np.testing.assert_array_equal(u[1, 0], data.experiments[1].u[64:128, 0])
    np.testing.assert_array_equal(y, 2 * u)


def test_frames_refuse_what_is_not_whole_periods():
    data = _data()
    with pytest.raises(DataError, match="not a whole number of periods of 50"):
        periodic_frames(data, period=50)
    with pytest.raises(ParameterError, match="period must be a whole number of samples >= 2"):
        periodic_frames(data, period=1.5)
    with pytest.raises(ParameterError, match="periods must be a whole number >= 1"):
        periodic_frames(data, periods=0)
    with pytest.raises(ParameterError, match="transient_periods must be a whole number"):
        periodic_frames(data, transient_periods=-1)
