"""The estimators' shared machinery (estimators/_base.py): declared ranges, the checks
of a regression problem, parameters and predictions, on a throwaway estimator."""

import numpy as np
import pytest

from blockid.errors import DataError, EstimationError, ParameterError
from blockid.estimators._base import Interval, RegressionEstimator, check_regression


@pytest.mark.parametrize(
    ("closed", "text", "inside"),
    [
        ("both", "[0, 1]", [True, True, True]),
        ("left", "[0, 1)", [True, True, False]),
        ("right", "(0, 1]", [False, True, True]),
        ("neither", "(0, 1)", [False, True, False]),
    ],
)
def test_an_interval_holds_its_ends_as_declared(closed, text, inside):
    interval = Interval(0.0, 1.0, closed)
    assert str(interval) == text
    assert [v in interval for v in (0.0, 0.5, 1.0)] == inside
    assert np.nan not in interval and np.inf not in Interval(0.0, None)


def test_an_open_ended_interval_reads_as_infinite():
    assert str(Interval(None, 2.5, "right")) == "(-inf, 2.5]"
    assert -1e300 in Interval(None, 2.5) and 3.0 not in Interval(None, 2.5)


def test_a_regression_problem_is_returned_as_float_columns():
    Phi, Y, one_d = check_regression([[1, 2], [3, 4]], [5, 6])
    assert one_d and Y.tolist() == [[5.0], [6.0]] and Phi.dtype == np.float64
    assert not check_regression(np.ones((2, 1)), np.ones((2, 3)))[2]


@pytest.mark.parametrize(
    ("Phi", "y", "message"),
    [
        (np.ones(3), np.ones(3), r"^Phi must be a 2-D array \(samples x regressors\), got shape \(3,\)$"),
        (np.ones((3, 1)), np.ones((3, 1, 1)), r"^y must be 1-D or 2-D \(samples x outputs\), got shape \(3, 1, 1\)$"),
        (np.ones((3, 1)), np.ones(2), r"^Phi has 3 rows but y has 2: give one target per regressor row$"),
        (np.ones((3, 1)), [0.0, 0.0, np.inf], r"^y contains NaN or inf \(first at row 2\); remove or fill"),
    ],
)  # fmt: skip
def test_a_bad_regression_problem_is_named(Phi, y, message):
    with pytest.raises(DataError, match=message):
        check_regression(Phi, y)


class _Mean(RegressionEstimator):
    """The smallest estimator: theta = the mean of y / the mean of the regressor."""

    _parameter_constraints = {"shrink": Interval(0.0, 1.0, "left")}

    def __init__(self, *, shrink: float = 0.0, label: str = "m") -> None:
        self.shrink = shrink
        self.label = label

    def fit(self, Phi, y):
        self._validate_params()
        Phi, Y, one_d = check_regression(Phi, y)
        self._theta = (1 - self.shrink) * (Y.mean(0) / Phi.mean(0)[:, None])
        self._one_d = one_d
        self._set_coef(self._theta, one_d)
        return self


def test_a_value_outside_its_declared_range_is_refused_naming_class_and_range():
    with pytest.raises(
        ParameterError, match=r"^_Mean: shrink=1\.0 is outside the allowed range \[0, 1\)$"
    ):
        _Mean(shrink=1.0).fit(np.ones((2, 1)), np.ones(2))
    with pytest.raises(ParameterError, match=r"shrink='x' is outside"):
        _Mean(shrink="x").fit(np.ones((2, 1)), np.ones(2))


def test_parameters_repr_coefficients_and_predictions():
    est = _Mean(shrink=0.5)
    assert est.get_params() == {"shrink": 0.5, "label": "m"}
    assert repr(est) == "_Mean(shrink=0.5, label='m')"
    with pytest.raises(EstimationError, match=r"^_Mean is not fitted yet; call fit\(\) first$"):
        est.predict(np.ones((1, 1)))
    est.fit(np.full((4, 1), 2.0), np.full(4, 6.0))  # theta = 0.5 * 6 / 2
    assert est.coef_.tolist() == [1.5] and est.predict([[2.0]]).tolist() == [3.0]
    est.fit(np.full((4, 1), 2.0), np.column_stack([np.full(4, 6.0), np.full(4, 2.0)]))
    assert est.coef_.tolist() == [[1.5], [0.5]]  # (targets, regressors)
    assert est.predict([[2.0]]).tolist() == [[3.0, 1.0]]
