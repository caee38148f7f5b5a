import numpy as np
import pytest

from blockid import errors
from blockid.evaluation import metrics_by_output


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
