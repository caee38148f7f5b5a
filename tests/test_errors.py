"""blockid's exceptions (blockid/errors.py): the parameter an error names, and that
every error a user can cause is a BlockidError and a ValueError."""

import numpy as np
import pytest

import blockid.errors as errors
from blockid.data import Dataset
from blockid.errors import BlockidError, DataError, EstimationError, ParameterError


def test_an_error_keeps_its_message_and_the_parameter_it_names():
    error = ParameterError("forgetting must be in (0, 1], got 2", parameter="forgetting")
    assert str(error) == "forgetting must be in (0, 1], got 2"
    assert error.parameter == "forgetting"
    assert DataError("no rows").parameter is None


def test_every_error_is_caught_as_a_blockid_error_and_as_a_value_error():
    for name in errors.__all__:
        with pytest.raises(ValueError) as caught:
            raise getattr(errors, name)("x")
        assert isinstance(caught.value, BlockidError), name


def test_a_library_data_error_is_caught_by_plain_value_error_handlers():
    with pytest.raises(ValueError, match="u") as caught:
        Dataset.from_arrays(np.zeros(5), np.zeros(4), ["u"], ["y"])
    assert isinstance(caught.value, DataError)


def test_an_estimation_error_carries_no_history_unless_one_is_attached():
    error = EstimationError("diverged")
    assert error.history is None
    error.history = {"theta": np.zeros((1, 2))}
    assert EstimationError("again").history is None  # not shared through the class
