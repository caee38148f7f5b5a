import json

import numpy as np
import pytest

from blockid import errors
from blockid.evaluation import fit_percent, max_absolute_error, metrics_by_output
from blockid.evaluation.metrics import json_safe


def test_values_against_hand_computation():
    y = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [4.0, 4.0]])
    yh = np.array([[1.0, 0.0], [2.5, 0.0], [3.0, 1.0], [2.0, 4.0]])
    m = metrics_by_output(y, yh, ["p0", "ma"])
    assert m["mse"]["p0"] == pytest.approx((0.25 + 4) / 4)
    assert m["rmse"]["p0"] == pytest.approx(np.sqrt(4.25 / 4))
    assert m["mae"]["ma"] == pytest.approx(0.25)
    assert m["max_abs_error"]["p0"] == pytest.approx(2.0)
    fit = 100 * (1 - np.sqrt(4.25) / np.sqrt(5.0))
    assert m["fit_percent"]["p0"] == pytest.approx(fit)
    assert set(m) == {"mse", "rmse", "mae", "max_abs_error", "fit_percent"}


def test_skip_and_errors():
    y = np.arange(5.0)
    m = metrics_by_output(y, y + np.array([9, 9, 0, 0, 0]), ["y"], skip=2)
    assert m["max_abs_error"]["y"] == 0.0
    with pytest.raises(errors.DataError, match="not finite"):
        metrics_by_output(y, y * np.nan, ["y"])
    with pytest.raises(errors.DataError, match="no samples left"):
        metrics_by_output(y, y, ["y"], skip=5)


def test_max_error_of_a_large_negative_error_is_its_magnitude():
    y = np.array([0.0, 1.0, 2.0, 3.0])
    y_hat = np.array([0.5, 1.0, 102.0, 2.75])  # errors y - y_hat: -0.5, 0, -100, 0.25
    m = metrics_by_output(y, y_hat, ["y"])
    assert m["max_abs_error"]["y"] == 100.0
    assert m["mae"]["y"] == (0.5 + 100.0 + 0.25) / 4
    assert m["mse"]["y"] == (0.25 + 10000.0 + 0.0625) / 4
    assert max_absolute_error(y, y_hat).tolist() == [100.0]
    # the same error with the sign flipped gives the same magnitudes
    assert metrics_by_output(y, 2 * y - y_hat, ["y"]) == m


def test_three_columns_are_scored_independently():
    # column 0: errors [1, -3, 0, 0]; column 1: perfect; column 2: errors [-0.5] * 4
    y = np.array([[1.0, 2.0, 0.0], [2.0, 4.0, 1.0], [3.0, 6.0, 2.0], [4.0, 8.0, 3.0]])
    y_hat = y + np.array([[-1.0, 0.0, 0.5], [3.0, 0.0, 0.5], [0.0, 0.0, 0.5], [0.0, 0.0, 0.5]])
    m = metrics_by_output(y, y_hat, ["a", "b", "c"])
    assert m["mse"] == {"a": 10.0 / 4, "b": 0.0, "c": 0.25}
    assert m["rmse"] == {"a": np.sqrt(2.5), "b": 0.0, "c": 0.5}
    assert m["mae"] == {"a": 1.0, "b": 0.0, "c": 0.5}
    assert m["max_abs_error"] == {"a": 3.0, "b": 0.0, "c": 0.5}
    # |y - mean|: a, c have squared deviations summing to 5; b to 20
    assert m["fit_percent"]["a"] == pytest.approx(100 * (1 - np.sqrt(10.0 / 5.0)))
    assert m["fit_percent"]["b"] == 100.0
    assert m["fit_percent"]["c"] == pytest.approx(100 * (1 - np.sqrt(1.0 / 5.0)))
    # each column alone gives the same numbers as inside the table
    for j, name in enumerate("abc"):
        alone = metrics_by_output(y[:, j], y_hat[:, j], [name])
        assert alone == {k: {name: v[name]} for k, v in m.items()}


def test_fit_percent_of_a_constant_output():
    y = np.full(4, 2.0)
    assert fit_percent(y, y).tolist() == [100.0]
    assert np.isnan(fit_percent(y, y + np.array([0.0, 0.0, 0.0, -1.0]))).all()  # undefined


# ---------------------------------------------------- found by mutation testing (docs/testing.md)
def test_undefined_notes_say_why_for_every_metric():
    from blockid.evaluation.metrics import undefined_notes

    notes = undefined_notes({"mse": {"y": float("nan")}, "fit_percent": {"y": 5.0}})
    assert notes == ["mse of output 'y' is undefined (null): not defined on these samples"]


def test_fit_percent_undefined_is_nan_and_json_null():
    y = np.full(4, 2.0)
    assert np.isnan(fit_percent(y, y + [0.0, 0.0, 0.0, 1.0])[0])
    assert json.dumps(json_safe({"a": [np.float64("nan"), -np.inf, 1.0]}), allow_nan=False) == (
        '{"a": [null, null, 1.0]}'
    )
