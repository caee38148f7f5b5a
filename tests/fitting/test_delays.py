"""Per-pair delays of a multivariable record, against the plant's."""

import numpy as np
import pytest

from blockid import errors
from blockid.data import Dataset, Experiment
from blockid.fitting.delays import channel_delays, channel_orders

from reference import mimo_delays_record as two_by_two


@pytest.mark.parametrize("delays", [((1, 6), (3, 7)), ((0, 4), (2, 0)), ((5, 1), (1, 9))])
def test_every_pairs_delay_is_the_plants(delays):
    found = channel_delays(two_by_two(delays))
    assert found.nk.tolist() == [list(r) for r in delays]
    assert found.as_option() == delays and not found.common
    # each pair's chosen delay has the smallest loss of its scan
    for i in range(2):
        for j in range(2):
            assert np.argmin(found.loss[i, j]) == found.nk[i, j]


def test_one_delay_for_every_pair_is_given_as_one_number():
    found = channel_delays(two_by_two(((2, 2), (2, 2))))
    assert found.common and found.as_option() == 2


def test_several_experiments_and_bad_requests():
    d = two_by_two(((1, 6), (3, 7)))
    e = d.experiments[0]
    parts = [Experiment("a", e.u[:700], e.y[:700]), Experiment("b", e.u[700:], e.y[700:])]
    split = Dataset(d.inputs, d.outputs, None, parts)
    assert channel_delays(split).nk.tolist() == [[1, 6], [3, 7]]
    with pytest.raises(errors.ParameterError, match="max_delay"):
        channel_delays(d, max_delay=-1)
    with pytest.raises(errors.ParameterError, match="nb"):
        channel_delays(d, nb=0)
    with pytest.raises(errors.DataError, match="too short.*smaller max_delay"):
        channel_delays(Dataset.from_arrays(e.u[:12], e.y[:12], ["u1", "u2"], ["y1", "y2"]))


def test_a_pair_whose_input_does_not_act_gets_no_delay_of_its_own():
    """A flat scan's longest 'best' delay means nothing: without evidence a pair takes
    the median of the pairs that have it (before: 9 and 10 on this diagonal plant)."""
    rng = np.random.default_rng(3)
    n = 1500
    u = np.repeat(rng.standard_normal((n // 3, 2)), 3, axis=0)
    y = np.zeros((n, 2))
    for t in range(4, n):
        y[t, 0] = 0.7 * y[t - 1, 0] + u[t - 2, 0]
        y[t, 1] = 0.5 * y[t - 1, 1] + 0.8 * u[t - 2, 1]
    y += 0.02 * rng.standard_normal(y.shape)
    found = channel_delays(Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"]))
    assert found.evidence.tolist() == [[True, False], [False, True]]
    assert found.nk.tolist() == [[2, 2], [2, 2]] and found.as_option() == 2
    # an input that never moves, and outputs that are noise: no evidence anywhere
    u[:, 1] = 0.5
    noise = rng.standard_normal((n, 2))
    found = channel_delays(Dataset.from_arrays(u, noise, ["u1", "u2"], ["y1", "y2"]))
    assert not found.evidence.any() and found.as_option() == 0


def test_too_few_rows_for_the_regression_are_refused_not_fitted_exactly():
    d = two_by_two(((1, 3), (2, 1)), n=30)
    e = d.experiments[0]
    short = Dataset.from_arrays(e.u[:16], e.y[:16], ["u1", "u2"], ["y1", "y2"])
    with pytest.raises(errors.DataError, match="regression rows for 7 coefficients"):
        channel_delays(short, max_delay=4)


# ---------------------------------------------------------------------- orders per pair
def _equation_noise_record(seed, n=1500, noise=0.05):
    """``nb = [[2, 1], [0, 1]]`` at delay 1 (input 1 does not act on output 2), white
    inputs and white equation noise: the model class the least-squares test assumes."""
    rng = np.random.default_rng(seed)
    u, e = rng.standard_normal((n, 2)), noise * rng.standard_normal((n, 2))
    y = np.zeros((n, 2))
    for t in range(3, n):
        y[t, 0] = (1.2 * y[t - 1, 0] - 0.4 * y[t - 2, 0] + 0.5 * u[t - 1, 0]
                   + 0.4 * u[t - 2, 0] + 0.3 * u[t - 1, 1] + e[t, 0])  # fmt: skip
        y[t, 1] = 0.6 * y[t - 1, 1] - 0.5 * u[t - 1, 1] + e[t, 1]
    return Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"])


@pytest.mark.parametrize("seed", range(5))
def test_every_pairs_number_of_coefficients_is_the_plants(seed):
    found = channel_orders(_equation_noise_record(seed), 1, 2, 3)
    assert found.nb.tolist() == [[2, 1], [0, 1]]
    assert found.as_option() == ((2, 1), (0, 1)) and not found.common
    assert found.loss.shape == (2, 2, 4)


def test_an_output_no_input_acts_on_keeps_its_best_pair():
    rng = np.random.default_rng(1)
    data = Dataset.from_arrays(rng.standard_normal((800, 2)), rng.standard_normal((800, 1)),
                               ["u1", "u2"], ["y"])  # fmt: skip
    found = channel_orders(data, 1, 2, 3)
    assert found.nb.sum() >= 1 and (found.nb > 0).sum() == 1  # an ARX needs an input


def test_orders_at_per_pair_delays_and_as_one_number():
    # the delays plant: nb = 1 on every pair at its own delay
    d = two_by_two(((1, 4), (3, 1)), noise=0.0)
    assert channel_orders(d, ((1, 4), (3, 1)), 2, 3).as_option() == 1
    # at one common delay, the late pairs need more coefficients to reach their lags
    assert channel_orders(d, 1, 2, 4).nb.tolist() == [[1, 4], [3, 1]]


def test_orders_bad_requests_are_named():
    d = _equation_noise_record(0, n=300)
    with pytest.raises(errors.ParameterError, match="nb_max"):
        channel_orders(d, 1, 2, 0)
    with pytest.raises(errors.ParameterError, match="nk must hold delays >= 0"):
        channel_orders(d, ((1, -1), (1, 1)), 2, 2)
    with pytest.raises(errors.DataError, match="too few to scan the pairs' orders"):
        channel_orders(Dataset.from_arrays(d.experiments[0].u[:30], d.experiments[0].y[:30],
                                           ["u1", "u2"], ["y1", "y2"]), 1, 2, 3)  # fmt: skip
