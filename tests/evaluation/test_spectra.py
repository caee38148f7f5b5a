"""What the BLA's estimates share (evaluation/spectra.py): levels in dB, excited lines, the
signals picked, missing samples named, the confidence and the unit of frequencies."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from blockid.data import Dataset
from blockid.data.dataset import Experiment
from blockid.evaluation.spectra import (
    DataError,
    ParameterError,
    check_confidence,
    check_finite,
    db,
    frequency_unit,
    powered,
    signal_columns,
)


def test_levels_and_excited_lines():
    assert db(np.array([1.0, 0.0, -1.0, 10.0])).tolist()[::3] == [0.0, 10.0]
    assert np.isnan(db(np.array([0.0])))[0]
    power = np.r_[np.zeros(5), np.ones(10), 0.02, 0.005]
    assert powered(power).tolist() == [False] * 5 + [True] * 11 + [False]
    assert not powered(np.zeros(4)).any()


def _two_by_one():
    u = np.ones((6, 2))
    return Dataset.from_arrays(u, np.ones(6), ["a", "b"], ["y"])


def test_the_bla_s_signals_are_picked_by_name_or_by_being_the_only_one():
    data = _two_by_one()
    assert signal_columns(data, "b", None) == (1, 0)
    with pytest.raises(
        ParameterError, match=r"^the data have 2 inputs \(a, b\); name the input of the BLA$"
    ) as caught:
        signal_columns(data, None, "y")
    assert caught.value.parameter == "input"
    with pytest.raises(ParameterError, match=r"^no output named 'z' \(the data have y\)$"):
        signal_columns(data, "a", "z")


def test_a_missing_sample_of_the_bla_s_signals_is_named_where_it_is():
    u, y = np.ones((6, 2)), np.ones(6)
    u[4, 0] = np.nan  # another column's gap does not matter
    y[3] = np.inf
    data = SimpleNamespace(experiments=[Experiment("e", u, y)])  # Dataset refuses gaps
    with pytest.raises(DataError, match=r"the input is nan at sample 4 \(0-based\); a frequency"):
        check_finite(data, 0, 0)
    with pytest.raises(DataError, match=r"the output is inf at sample 3 \(0-based\)"):
        check_finite(data, 1, 0)


def test_confidence_and_the_unit_of_frequencies():
    assert check_confidence("0.95") == 0.95
    with pytest.raises(
        ParameterError, match=r"^confidence must lie between 0 and 1 \(e\.g\. 0\.99\), got 1$"
    ):
        check_confidence(1)
    assert (frequency_unit(0.01), frequency_unit(None)) == ("Hz", "cycles/sample")
