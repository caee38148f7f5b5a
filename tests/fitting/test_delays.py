"""Per-pair delays of a multivariable record, against the plant's."""

import numpy as np
import pytest

from blockid import errors
from blockid.data import Dataset, Experiment
from blockid.fitting.delays import channel_delays


def two_by_two(delays, n=1500, seed=0, noise=0.02):
    """A coupled 2-input 2-output ARX plant; ``delays[i][j]``: of input j in output i."""
    (a, b), (c, d) = delays
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.standard_normal((n // 3, 2)), 3, axis=0)
    y = np.zeros((n, 2))
    for t in range(10, n):
        y[t, 0] = 1.2 * y[t - 1, 0] - 0.4 * y[t - 2, 0] + 0.5 * u[t - a, 0] + 0.3 * u[t - b, 1]
        y[t, 1] = 0.6 * y[t - 1, 1] + 0.6 * u[t - c, 0] - 0.5 * u[t - d, 1]
    y += noise * rng.standard_normal(y.shape)
    return Dataset.from_arrays(u, y, ["u1", "u2"], ["y1", "y2"])


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
