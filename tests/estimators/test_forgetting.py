"""Forgetting schedules (estimators/forgetting.py): parsing, the factor of every
sample, and the refusals."""

import pytest

from blockid import errors
from blockid.estimators import ForgettingSchedule


def test_schedule_parsing():
    s = ForgettingSchedule.parse("0.9:2,0.95:3,1")
    assert s.factors(0, 7).tolist() == [0.9, 0.9, 0.95, 0.95, 0.95, 1.0, 1.0]
    assert s.factors(3, 3).tolist() == [0.95, 0.95, 1.0]
    assert str(ForgettingSchedule.parse(0.99)) == "0.99"
    with pytest.raises(errors.ParameterError, match="expected a number"):
        ForgettingSchedule.parse("0.9,0.8")
